# quad
Vertex 1 0 0 0 {uv=(0 0) rgb=(1 0 0) normal=(0 0 1)}
Vertex 2 1 0 0 {uv=(1 0) rgb=(0 1 0) normal=(0 0 1)}
Vertex 5 1 1 0 {uv=(1 1) rgb=(0 0 1) normal=(0 0 0)}
Vertex 7 0 1 0 {uv=(0 1) rgb=(1 1 1) normal=(0 0 1) wid=3 father=(2)}
Face 1 1 2 5 7 {sharp}
Edge 1 2

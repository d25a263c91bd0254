# A unit quad in the z = 0 plane facing +z, with uv and rgb per vertex (made for whitted's tests).
Vertex 1 -1 -1 0 {normal=(0 0 1) uv=(0 0) rgb=(1 0 0)}
Vertex 2  1 -1 0 {normal=(0 0 1) uv=(1 0) rgb=(0 1 0)}
Vertex 3  1  1 0 {normal=(0 0 1) uv=(1 1) rgb=(0 0 1)}
Vertex 4 -1  1 0 {normal=(0 0 1) uv=(0 1) rgb=(1 1 1)}
Face 1 1 2 3
Face 2 1 3 4

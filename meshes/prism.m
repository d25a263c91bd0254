# A needle-thin closed triangular prism (1000:1), for watertightness tests (made for whitted).
Vertex 1 0 0 0
Vertex 2 0.001 0 0
Vertex 3 0 0.001 0
Vertex 4 0 0 1
Vertex 5 0.001 0 1
Vertex 6 0 0.001 1
Face 1 1 3 2
Face 2 4 5 6
Face 3 1 2 5
Face 4 1 5 4
Face 5 2 3 6
Face 6 2 6 5
Face 7 3 1 4
Face 8 3 4 6

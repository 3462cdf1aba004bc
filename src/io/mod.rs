//! Mesh file formats for the CLI and tests: PLY, STL, OBJ (+ Teeth3DS JSON labels), VTK.

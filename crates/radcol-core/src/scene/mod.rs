//! Scenes for graphics users: triangle meshes with materials (OBJ files, built-ins, vertex/index buffers).

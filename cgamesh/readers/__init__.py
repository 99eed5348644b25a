"""Readers of exported files (glTF, USD, OBJ, PLY, STL) as meshes, for the quality report and checks.

Every reader distrusts its file: sizes, counts and referenced files are checked before
anything is allocated or opened.

    readback.py        each format read back as SurfaceMeshes (read_gltf, read_usd, read_trimesh)
    gltf_reader.py     glTF / GLB: the JSON, buffers and accessors, checked
    files.py           the files a mesh file names, read only inside its own folder
    library_calls.py   format libraries' diagnostics captured into one line
    usd_sandbox.py     USD read in a child process with memory and time limits (the parent's side)
    usd_child.py       that child's side: read one file, hand back its arrays
"""

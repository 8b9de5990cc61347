# SPDX-License-Identifier: MIT
"""Scene files: the reader, its expressions, Gmsh meshes, the scene keys and their located errors."""

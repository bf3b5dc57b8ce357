"""gmsh meshes of quasi-quarter-space wheel and rail bodies for FE influence numbers.

:mod:`conformal.meshing.bodies` says what to mesh (body, contact patch, extent) and
:mod:`conformal.meshing.gmsh_body` meshes it (gmsh is imported only when a mesh is made).
"""
from conformal.meshing.bodies import BodyExtent, BodyModel, Profile2D, StripPatch, body_extent, flat_profile
from conformal.meshing.gmsh_body import BodyMesh, MeshingError, MeshSpec, mesh_body

__all__ = ["BodyExtent", "BodyModel", "Profile2D", "StripPatch", "body_extent", "flat_profile",
           "BodyMesh", "MeshingError", "MeshSpec", "mesh_body"]

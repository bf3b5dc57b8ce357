"""Direct FE contact of two elastic bodies (theory ``"fe_contact"``): the independent oracle for
the influence-number models.

Layers: :mod:`.solver` (FE assembly, node-to-surface pairing, Signorini by a primal-dual active
set; receives meshed bodies), :mod:`.bodies` (gmsh meshes of Hertzian pairs and of the wheel and
rail of a curved grid), :mod:`.problems` (the glue from scene problems to bodies and back to a
:class:`~conformal.result.Result`, VTU export).
"""
from conformal.fe_contact.solver import (ContactBody, ContactModel, FEContactError, FEContactSettings,
                                         FEContactSolution, boussinesq, pair_surfaces, prepare_contact,
                                         recovered_pressure, solve_contact)

__all__ = ["ContactBody", "ContactModel", "FEContactError", "FEContactSettings", "FEContactSolution", "boussinesq",
           "pair_surfaces", "prepare_contact", "recovered_pressure", "solve_contact"]

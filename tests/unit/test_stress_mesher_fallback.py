"""The stress bodies' mesher falls back to gmsh's next 3-D algorithm when one aborts the process.

gmsh aborts (SIGABRT, heap corruption) rather than raising on some slab bodies; the meshing runs in
a forked child so that the caller survives, and the next algorithm is tried.  Here the mesher is
replaced by one that aborts for Delaunay (1) and answers for Frontal (4), and by one that always
aborts, which must end in one FESolveError naming the algorithms tried.
"""
import os
import signal

import pytest

from conformal.influence.factor import FESolveError
from conformal.stresses import bodies


class _Model:
    kind = "wheel"


def _die():
    os.kill(os.getpid(), signal.SIGKILL)   # as gmsh's abort: the child ends without an answer


def _abort_for_delaunay(model, patch, spec, algorithm3d):
    if algorithm3d == 1:
        _die()
    return ("meshed", algorithm3d)


def _always_abort(model, patch, spec, algorithm3d):
    _die()


def test_next_algorithm_after_an_abort(monkeypatch):
    monkeypatch.setattr(bodies, "mesh_body", _abort_for_delaunay)
    assert bodies._mesh_isolated(_Model(), None, None) == ("meshed", 4)


def test_every_algorithm_aborting_is_one_error(monkeypatch):
    monkeypatch.setattr(bodies, "mesh_body", _always_abort)
    with pytest.raises(FESolveError, match=r"wheel body \(3-D algorithms 1, 4\)"):
        bodies._mesh_isolated(_Model(), None, None)

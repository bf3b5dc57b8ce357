"""The memory check of a grid reads the available memory only for grids that could exhaust it."""
import pytest

from conformal import scene as sc
from conformal.errors import InputError


def test_small_grids_skip_the_memory_read_large_ones_are_refused(monkeypatch):
    reads = []

    def tiny():
        reads.append(1)
        return 1e6                      # 1 MB left: every grid above SMALL_GRID_BYTES must be refused
    monkeypatch.setattr(sc, "available_memory", tiny)
    small = sc.grid_bytes(60, 80, "exact")
    assert small < sc.SMALL_GRID_BYTES
    sc.check_grid_memory(60, 80, "exact", "[grid] n")          # a sweep's patch grid: no read, no refusal
    assert reads == []
    n = 2
    while sc.grid_bytes(n, n, "exact") <= sc.SMALL_GRID_BYTES:
        n *= 2
    with pytest.raises(InputError, match="needs about"):
        sc.check_grid_memory(n, n, "exact", "[grid] n")
    assert reads == [1]

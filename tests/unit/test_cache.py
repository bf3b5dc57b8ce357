"""Cache of FE influence numbers (conformal.influence.cache), the CONTACT-style influence file and
the ``conformal cache`` command."""
from __future__ import annotations

import zipfile

import numpy as np
import pytest

from conformal.cli import main
from conformal.errors import InputError
from conformal.influence import fe
from conformal.influence.cache import Cache, CacheWarning, default_dir
from conformal.influence.contact_file import read_influence_file, write_influence_file
from conformal.meshing.bodies import BodyModel, StripPatch, flat_profile

G, NU = 82000.0, 0.28


@pytest.fixture
def cache(tmp_path):
    return Cache(tmp_path / "cache")


def test_key_depends_on_every_input(cache):
    base = {"a": 1.0, "arr": np.arange(3.0), "nested": {"x": [1, 2]}}
    k = cache.key(base)
    assert k == cache.key({"nested": {"x": [1, 2]}, "arr": np.arange(3.0), "a": 1.0})   # order-free
    for change in ({"a": 1.0 + 1e-15}, {"arr": np.arange(3.0) + [0, 0, 1e-12]}, {"nested": {"x": [1, 3]}}):
        assert cache.key({**base, **change}) != k


def test_store_load_and_atomic_files(cache):
    inputs = {"what": "t", "n": 2}
    key = cache.key(inputs)
    cache.store(key, inputs, {"kernel": np.eye(3)}, {"summary": "test"})
    assert np.array_equal(cache.load(key, inputs)["kernel"], np.eye(3))
    assert not list(cache.folder.glob(".*.tmp"))
    with zipfile.ZipFile(cache.path(key)) as z:             # metadata stored inside the NPZ
        assert "__meta__.npy" in z.namelist()
    assert cache.meta(key)["inputs"] == {"n": 2, "what": "t"}


def test_corrupt_or_foreign_files_are_rejected(cache):
    inputs = {"what": "t"}
    key = cache.key(inputs)
    cache.store(key, inputs, {"kernel": np.arange(10.0)})
    # 1. truncated file
    data = cache.path(key).read_bytes()
    cache.path(key).write_bytes(data[: len(data) // 2])
    with pytest.warns(CacheWarning, match="cannot be read"):
        assert cache.load(key, inputs) is None
    assert not cache.path(key).exists()                       # removed, will be recomputed
    # 2. a valid file under the wrong name (foreign key)
    other = {"what": "other"}
    cache.store(cache.key(other), other, {"kernel": np.arange(10.0)})
    cache.path(cache.key(other)).rename(cache.path(key))
    with pytest.warns(CacheWarning, match="another key"):
        assert cache.load(key, inputs) is None
    # 3. array changed behind the checksum's back
    cache.store(key, inputs, {"kernel": np.arange(10.0)})
    with np.load(cache.path(key)) as z:
        meta = str(z["__meta__"])
    np.savez(cache.path(key), kernel=np.arange(10.0) + 1.0, __meta__=np.array(meta))
    with pytest.warns(CacheWarning, match="checksum"):
        assert cache.load(key, inputs) is None
    # 4. same key, different inputs recorded (hash collision or edited file)
    cache.store(key, {"what": "t2"}, {"kernel": np.arange(10.0)})
    with pytest.warns(CacheWarning, match="different inputs"):
        assert cache.load(key, inputs) is None


def test_failed_computation_leaves_nothing(cache):
    def compute():
        raise MemoryError("simulated")

    with pytest.raises(MemoryError):
        cache.get_or_compute({"what": "x"}, compute)
    assert not cache.folder.exists() or not any(cache.folder.iterdir())


def test_default_folder_from_environment(monkeypatch, tmp_path):
    monkeypatch.setenv("CONFORMAL_CACHE", str(tmp_path / "c"))
    assert default_dir() == tmp_path / "c"
    monkeypatch.delenv("CONFORMAL_CACHE")
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    assert default_dir().name == "conformal"


def test_fe_kernel_cached_and_version_keyed(cache, monkeypatch):
    body = BodyModel("block", flat_profile(-20, 20))
    patch = StripPatch.uniform(2, 1.0, 2, 1.0, 20.0)
    a = fe.cached_body_influence(body, patch, G, NU, cache=cache)
    b = fe.cached_body_influence(body, patch, G, NU, cache=cache)
    assert not a.stats.get("cache_hit") and b.stats["cache_hit"]
    assert np.array_equal(a.kernel, b.kernel) and len(cache.entries()) == 1
    monkeypatch.setattr(fe, "FE_VERSION", fe.FE_VERSION + "-changed")
    c = fe.cached_body_influence(body, patch, G, NU, cache=cache)
    assert not c.stats.get("cache_hit") and len(cache.entries()) == 2
    # a failing solve writes nothing
    monkeypatch.setattr(fe, "_available_memory", lambda: 1.0)
    with pytest.raises(fe.FESolveError):
        fe.cached_body_influence(body, StripPatch.uniform(3, 1.0, 2, 1.0, 20.0), G, NU, cache=cache)
    assert len(cache.entries()) == 2 and not list(cache.folder.glob(".*.tmp"))


def test_cache_command(cache, capsys):
    for n in range(2):
        inputs = {"n": n}
        cache.store(cache.key(inputs), inputs, {"kernel": np.zeros(4)}, {"summary": f"entry {n}"})
    assert main(["cache", "list", "--cache", str(cache.folder)]) == 0
    out = capsys.readouterr().out
    assert "entry 0" in out and "entry 1" in out and "2 entries" in out
    assert main(["cache", "clear", "--cache", str(cache.folder)]) == 0
    assert "removed 2" in capsys.readouterr().out and cache.entries() == []


# ----------------------------------------------------------------------------- influence file
def test_influence_file_round_trip_fe_kernel(tmp_path):
    body = BodyModel("block", flat_profile(-20, 20))
    patch = StripPatch.uniform(3, 0.5, 2, 0.7, 20.0)
    K = fe.body_influence(body, patch, G, NU).kernel
    path = tmp_path / "fe.inf"
    write_influence_file(path, K, dx=patch.dx, s_edges=patch.edges, comments=["flat block"])
    f = read_influence_file(path)
    assert np.array_equal(f.kernel, K)                        # %.17g: exact
    assert f.mx == 3 and f.ms == 2 and f.dx == 0.5 and np.array_equal(f.s_edges, patch.edges)
    assert f.comments == ("flat block",)
    # it feeds the curved-strip operator directly
    from conformal.influence.curved import CurvedInfluence

    op = CurvedInfluence.from_kernel(f.kernel)
    assert op.dense().shape == (3 * 3 * 2, 3 * 3 * 2)


def test_influence_file_bad_input(tmp_path):
    K = np.zeros((3, 2, 2, 3, 3))
    p = tmp_path / "a.inf"
    write_influence_file(p, K, dx=1.0, s_edges=[0, 1, 2])
    lines = p.read_text().splitlines()
    (tmp_path / "short.inf").write_text("\n".join(lines[:-1]))
    with pytest.raises(InputError, match="expected 12 data lines"):
        read_influence_file(tmp_path / "short.inf")
    (tmp_path / "dup.inf").write_text("\n".join(lines[:-1] + [lines[-2]]))
    with pytest.raises(InputError, match="missing or repeated"):
        read_influence_file(tmp_path / "dup.inf")
    (tmp_path / "other.inf").write_text("something else\n")
    with pytest.raises(InputError, match="not a 'conformal-influence 1'"):
        read_influence_file(tmp_path / "other.inf")
    with pytest.raises(InputError, match="shape"):
        write_influence_file(p, np.zeros((2, 2, 2, 3, 3)), dx=1.0, s_edges=[0, 1, 2])
    with pytest.raises(InputError, match="not found"):
        read_influence_file(tmp_path / "missing.inf")

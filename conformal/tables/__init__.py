"""Creep-force tables from the exact theory (Kalker's USETAB idea), built as distributed jobs.

* :mod:`conformal.tables.spec`: the table definition, normalisation (Eqs. T1-T4) and SPEC.toml;
* :mod:`conformal.tables.build`: one exact steady-rolling solve per node, chunked, resumable,
  local processes or Dask (``conformal table build``);
* :mod:`conformal.tables.table`: the NPZ file (metadata, content hash) and the vectorised
  evaluator :func:`evaluate`;
* :mod:`conformal.tables.model`: ``[model] theory = "table"``.

>>> from conformal.tables import evaluate, load_table
>>> FX, FY, MZ = evaluate(load_table(), 6.0, 6.0, 1e5, 0.3, 82000.0, 0.28, 0.03, 0.0, 0.0)
>>> round(float(FX) / 3e4, 2)
-1.0
"""
import importlib

#: the public names and their modules, imported on first use (PEP 562): ``conformal table`` and
#: ``conformal --help`` need the package but not numpy or the build machinery
_NAMES = {"BuildReport": "build", "build_table": "build", "TableSpec": "spec", "load_spec": "spec",
          "spec_from_dict": "spec", "CreepTable": "table", "DEFAULT_TABLE": "table", "evaluate": "table",
          "load_table": "table", "save_table": "table"}

__all__ = ["BuildReport", "CreepTable", "DEFAULT_TABLE", "TableSpec", "build_table", "evaluate", "load_spec",
           "load_table", "save_table", "spec_from_dict"]


def __getattr__(name: str):
    if name in _NAMES:
        value = getattr(importlib.import_module(f"conformal.tables.{_NAMES[name]}"), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'conformal.tables' has no attribute {name!r}")

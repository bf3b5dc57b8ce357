"""Creep-force tables from the exact theory (Kalker's USETAB idea), built as distributed jobs.

* :mod:`conformal.tables.spec`: the table definition, normalisation (Eqs. T1-T4) and SPEC.toml;
* :mod:`conformal.tables.build`: one exact steady-rolling solve per node, chunked, resumable,
  local processes or Dask (``conformal table build``);
* :mod:`conformal.tables.table`: the NPZ file (metadata, content hash) and the vectorised
  evaluator :func:`evaluate`;
* :mod:`conformal.tables.model`: ``[model] theory = "table"``.

>>> FX, FY, MZ = evaluate(load_table(), 6.0, 6.0, 1e5, 0.3, 82000.0, 0.28, 0.03, 0.0, 0.0)
>>> round(float(FX) / 3e4, 2)
-1.0
"""
from conformal.tables.build import BuildReport, build_table
from conformal.tables.spec import TableSpec, load_spec, spec_from_dict
from conformal.tables.table import CreepTable, DEFAULT_TABLE, evaluate, load_table, save_table

__all__ = ["BuildReport", "CreepTable", "DEFAULT_TABLE", "TableSpec", "build_table", "evaluate", "load_spec",
           "load_table", "save_table", "spec_from_dict"]

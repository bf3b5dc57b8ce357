"""Reference pages generated from the code when the documentation is built.

Three generators, each a pure function from the package to Markdown text, and one Sphinx hook
(``builder-inited``) that writes their output under ``docs/reference/_generated/`` (not tracked):

* :func:`scene_keys_markdown`: the scene keys, with units and defaults, from the scene layer.
  **This is the one place that knows where the model tables live**: it reads
  ``conformal.scene`` (``THEORIES``, ``INFLUENCES``, ``GEOMETRY_KINDS``, ``MODEL_OPTIONS`` and the
  frozen dataclasses of the sections) and ``conformal.specs``.  When a model registry replaces
  those tables, only :func:`_scene_tables` changes.
* :func:`cli_markdown`: every command and option of ``conformal`` from the argparse parser
  (``conformal.cli.build_parser``).
* :func:`api_pages`: one page per module group of the package, each an ``automodule`` directive
  (the text comes from the numpydoc docstrings through autodoc and napoleon).
"""
from __future__ import annotations

import argparse
import dataclasses
import importlib
import inspect
import math
import pkgutil
import re
from pathlib import Path

# --------------------------------------------------------------------------------------- scene keys

#: units and one-line meanings of the keys whose dataclass field has no trailing comment, and of
#: the TOML names that are not dataclass fields ([material], [friction]).  Everything else comes
#: from the code: the field names, their defaults and the comment on the field's line.
_KEY_NOTES = {
    "material": {
        "G": ("N/mm²", "shear modulus of both bodies (or E)"),
        "E": ("N/mm²", "Young's modulus of both bodies (or G)"),
        "nu": ("-", "Poisson's ratio, -1 < nu < 0.5"),
        "body2": ("table", "[material.body2] with its own G or E and nu (dissimilar bodies)"),
    },
    "friction": {
        "mu": ("-", "Coulomb coefficient, > 0 (static = kinetic)"),
        "mu_static": ("-", "static coefficient (with mu_kinetic)"),
        "mu_kinetic": ("-", "kinetic coefficient, <= mu_static"),
        "mu_table": ("file", "rows s, mu: friction varying over the profile (theory exact)"),
    },
    "geometry": {
        "A": ("1/mm", "quadratic: h = A x² + B y²"),
        "B": ("1/mm", "quadratic: B = 0 is line contact (plane strain)"),
        "a": ("mm", "hertz: semi-axis along x (rolling)"),
        "b": ("mm", "hertz: semi-axis along y"),
        "file": ("file", "table: undeformed distance, mx rows of my numbers"),
        "wheel_profile": ("-", "file (CSV y,z or CONTACT .prw) or a built-in name"),
        "rail_profile": ("-", "file (CSV y,z or CONTACT .prr) or a built-in name"),
        "side": ("-", "\"left\" | \"right\""),
    },
    "load": {
        "normal_force": ("N", "prescribed normal force (per mm of line in line contact)"),
        "approach": ("mm", "prescribed approach; wheel-rail: lowering below the first touch"),
        "wheel_load": ("N", "vertical wheel load (wheel-rail scenes)"),
        "load_angle": ("rad", "direction of the wheel load, 0 = vertical (theory conformal)"),
    },
    "kinematics": {
        "xi": ("- or mm", "longitudinal creepage (shift: rigid shift, mm)"),
        "eta": ("- or mm", "lateral creepage (shift: rigid shift, mm)"),
        "phi": ("rad/mm or rad", "spin creepage (shift: rotation, rad)"),
        "rolling": ("-", "\"steady\" | \"shift\""),
        "fx_rel": ("-", "prescribed FX/(mu FN) instead of xi"),
        "fy_rel": ("-", "prescribed FY/(mu FN) instead of eta"),
    },
    "grid": {
        "mx": ("-", "explicit grid: elements along x"), "my": ("-", "explicit grid: elements along y"),
        "dx": ("mm", "explicit grid: element length along x"), "dy": ("mm", "explicit grid: element width"),
        "xl": ("mm", "explicit grid: lower x corner"), "yl": ("mm", "explicit grid: lower y corner"),
        "n": ("-", "automatic grid: elements along each axis"),
        "scale": ("-", "automatic grid: extent over the Hertz patch"),
    },
    "model": {
        "theory": ("-", "the model, one of the theories below"),
        "tol": ("-", "relative stopping tolerance of the iterations, <= 1e-2"),
        "maxit": ("-", "iteration limit"),
    },
    "history": {
        "normal_force": ("N", "normal load of this step"), "approach": ("mm", "approach of this step"),
        "xi": ("mm or -", "shift increment (shift) or creepage"), "eta": ("mm or -", "as xi, lateral"),
        "phi": ("rad or rad/mm", "rotation increment or spin"),
        "rolling": ("-", "\"shift\" | \"transient\" | \"steady\""),
        "distance": ("mm", "rolled distance of a transient step"),
        "fx_rel": ("-", "prescribed FX/(mu FN)"), "fy_rel": ("-", "prescribed FY/(mu FN)"),
        "repeat": ("-", "the step applied this many times"),
    },
}


#: a unit at the start of a field comment ("mm, nominal rolling radius", "rad; None = ...")
_UNIT = re.compile(r"^(mm/\(N/mm²\)|mm/s|rad/s|mm|rad|N)(?:[,;]\s*|\s+|$)(.*)$")


def _field_comments(cls) -> dict[str, str]:
    """The trailing ``# ...`` comment of each field line of a dataclass (its unit and meaning)."""
    try:
        lines, _ = inspect.getsourcelines(cls)
    except (OSError, TypeError):
        return {}
    out = {}
    for line in lines:
        code, sep, comment = line.partition("#")
        if not sep or ":" not in code:
            continue
        name = code.split(":")[0].strip()
        if name.isidentifier():
            out[name] = comment.strip().lstrip(":").strip()
    return out


def _default(f: dataclasses.Field):
    if f.default is not dataclasses.MISSING:
        return f.default
    if f.default_factory is not dataclasses.MISSING:      # type: ignore[misc]
        return f.default_factory()                        # type: ignore[misc]
    return None


def _fmt(v) -> str:
    if v is None:
        return "-"
    if isinstance(v, float):
        if v == math.atan(1 / 40):
            return "atan(1/40)"
        return f"{v:g}"
    if isinstance(v, str):
        return f'"{v}"'
    return str(v)


def _scene_tables():
    """What the scene layer knows about its keys, in one structure.

    Returns ``(sections, theories, influences, kinds, model_options)`` where ``sections`` maps a
    TOML section to rows ``(key, default, unit, meaning)``.  Switch this function to the model
    registry when it exists; the renderer below stays.
    """
    from conformal import scene, specs

    sections: dict[str, list[tuple[str, str, str, str]]] = {}

    def rows(section: str, classes, skip=("kind", "options")):
        seen, out = set(), []
        notes = _KEY_NOTES.get(section, {})
        for cls in classes:
            comments = _field_comments(cls)
            for f in dataclasses.fields(cls):
                if f.name in skip or f.name in seen:
                    continue
                seen.add(f.name)
                unit, meaning = notes.get(f.name, ("", ""))
                comment = comments.get(f.name, "")
                if comment and not meaning:
                    m = _UNIT.match(comment)
                    if m and not unit:
                        unit, meaning = m.group(1), m.group(2)
                    else:
                        meaning = comment
                out.append((f.name, _fmt(_default(f)), unit or "", meaning))
        return out

    sections["material"] = [(k, "-" if k in ("E", "body2") else "required", u, m)
                            for k, (u, m) in _KEY_NOTES["material"].items()]
    sections["friction"] = [(k, "0.3" if k == "mu" else "-", u, m) for k, (u, m) in _KEY_NOTES["friction"].items()]
    sections["geometry"] = [("kind", "required", "-", " | ".join(f'"{k}"' for k in scene.GEOMETRY_KINDS))]
    sections["geometry"] += rows("geometry", (scene.QuadraticGeometry, scene.HertzGeometry,
                                              scene.TableGeometry, scene.WheelRailGeometry))
    sections["load"] = rows("load", (scene.Load,))
    sections["kinematics"] = rows("kinematics", (specs.Kinematics,))
    sections["grid"] = rows("grid", (scene.GridSpec,))
    sections["model"] = rows("model", (specs.ModelSpec,))
    sections["[history]"] = rows("history", (specs.HistoryStep,))
    return sections, scene.THEORIES, scene.INFLUENCES, scene.GEOMETRY_KINDS, dict(scene.MODEL_OPTIONS)


def _cell(text: str) -> str:
    return str(text).replace("|", "\\|").replace("\n", " ")


def scene_keys_markdown() -> str:
    """The scene keys as Markdown tables (one per TOML section)."""
    sections, theories, influences, _kinds, options = _scene_tables()
    out = ["# Scene keys (generated)", "",
           "Generated from the scene layer of the package when the documentation is built "
           "(`docs/_ext/generated.py`). Units: mm, N, N/mm², rad; a key that is not listed is refused "
           "with the closest known name. A `-` default means: not set (the key is optional or one of "
           "a set of alternatives; see [Scene files](../scene-files.md)).", ""]
    for section, rows in sections.items():
        out += [f"## `[{section}]`", "", "| key | default | unit | meaning |", "|---|---|---|---|"]
        out += [f"| `{k}` | {_cell(d)} | {_cell(u)} | {_cell(m)} |" for k, d, u, m in rows]
        out.append("")
    out += ["## `[model] theory`", "", "One of: " + ", ".join(f"`{t}`" for t in theories) + ".", "",
            "## `[model] influence`", "", "One of: " + ", ".join(f"`{t}`" for t in influences) + ".", "",
            "## Model-specific `[model]` options", "",
            "Checked on reading whatever the theory; any other key is refused.", "",
            "| key | model and meaning |", "|---|---|"]
    out += [f"| `{k}` | {_cell(v)} |" for k, v in sorted(options.items())]
    out.append("")
    return "\n".join(out)


# ----------------------------------------------------------------------------------------- the CLI

def _usage(parser: argparse.ArgumentParser) -> str:
    return " ".join(parser.format_usage().split())[len("usage: "):]


def _command_sections(prog: str, parser: argparse.ArgumentParser, help_text: str) -> list[str]:
    """One section per command, then one per sub-command (``conformal table build``, ...)."""
    out = [f"## `{prog}`", "", _cell(help_text or parser.description or ""), "",
           "```text", _usage(parser), "```", ""]
    rows, nested = [], []
    for a in parser._actions:
        if isinstance(a, argparse._HelpAction):
            continue
        if isinstance(a, argparse._SubParsersAction):
            helps = {c.dest: c.help for c in a._choices_actions}
            for name, sub in a.choices.items():
                rows.append(f"| `{name}` | {_cell(helps.get(name) or '')} (`{prog} {name}`, below) |")
                nested.append((f"{prog} {name}", sub, helps.get(name) or ""))
            continue
        names = ", ".join(a.option_strings) or a.dest
        if a.metavar and a.option_strings:
            names += f" {a.metavar}"
        text = a.help or ""
        if a.choices and not isinstance(a.choices, dict):
            text += f" (one of: {', '.join(map(str, a.choices))})"
        rows.append(f"| `{_cell(names)}` | {_cell(text)} |")
    if rows:
        out += ["| argument | meaning |", "|---|---|", *rows, ""]
    for sub_prog, sub, text in nested:
        out += _command_sections(sub_prog, sub, text)
    return out


def cli_markdown() -> str:
    """Every ``conformal`` command with its options, from the argparse parser."""
    from conformal.cli import build_parser

    parser = build_parser()
    out = ["# Commands (generated)", "",
           "Generated from `conformal.cli.build_parser` when the documentation is built. "
           "`conformal COMMAND --help` prints the same.", "",
           "```text", _usage(parser), "```", ""]
    for a in parser._actions:
        if isinstance(a, argparse._SubParsersAction):
            helps = {c.dest: c.help for c in a._choices_actions}
            for name, sub in a.choices.items():
                out += _command_sections(f"conformal {name}", sub, helps.get(name) or "")
    return "\n".join(out)


# ----------------------------------------------------------------------------------------- the API

#: private modules and modules left out of the API reference
_API_SKIP = {"conformal._threads"}


def _modules(package: str = "conformal") -> list[str]:
    pkg = importlib.import_module(package)
    names = [package]
    for info in pkgutil.walk_packages(pkg.__path__, package + "."):
        if info.name.split(".")[-1].startswith("_") or info.name in _API_SKIP:
            continue
        names.append(info.name)
    return sorted(names)


def api_pages() -> dict[str, str]:
    """Page name -> Markdown: one page per top-level module or sub-package of ``conformal``."""
    groups: dict[str, list[str]] = {}
    for name in _modules():
        parts = name.split(".")
        key = parts[1] if len(parts) > 1 else "conformal"
        groups.setdefault(key, []).append(name)
    pages = {}
    for key, mods in sorted(groups.items()):
        title = "conformal" if key == "conformal" else f"conformal.{key}"
        body = [f"# `{title}`", ""]
        for m in mods:
            if len(mods) > 1:
                body += [f"## `{m}`", ""]
            body += ["```{eval-rst}", f".. automodule:: {m}", "   :members:", "```", ""]
        pages[key] = "\n".join(body) + "\n"
    index = ["# API reference (generated)", "",
             "One page per module of the package, from the numpydoc docstrings.", "",
             "```{toctree}", ":maxdepth: 1", ""] + [f"api_{k}" for k in sorted(pages)] + ["```", ""]
    out = {f"api_{k}.md": v for k, v in pages.items()}
    out["api.md"] = "\n".join(index)
    return out


# ------------------------------------------------------------------------------------------ the hook

def _write(path: Path, text: str) -> None:
    """Write only when the text changed (keeps Sphinx's incremental builds incremental)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    if not path.exists() or path.read_text(encoding="utf-8") != text:
        path.write_text(text, encoding="utf-8")


def generate(srcdir: Path) -> list[Path]:
    """Write the generated pages under ``srcdir/reference/_generated``; returns their paths."""
    folder = Path(srcdir) / "reference" / "_generated"
    files = {"scene_keys.md": scene_keys_markdown(), "cli.md": cli_markdown(), **api_pages()}
    for name, text in files.items():
        _write(folder / name, text)
    for stale in folder.glob("*.md"):
        if stale.name not in files:
            stale.unlink()
    return [folder / n for n in files]


def _on_builder_inited(app) -> None:
    generate(Path(app.srcdir))


def setup(app):
    app.connect("builder-inited", _on_builder_inited)
    return {"version": "1", "parallel_read_safe": True, "parallel_write_safe": True}


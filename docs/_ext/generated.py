"""Reference pages generated from the code when the documentation is built.

Four generators, each a pure function from the package to Markdown text, and one Sphinx hook
(``builder-inited``) that writes their output under ``docs/reference/_generated/`` (not tracked):

* :func:`scene_keys_markdown`: the scene keys, with units and defaults, from the model registry
  (``conformal.registry``) through ``conformal.scene.reference_markdown``.
* :func:`schema_markdown`: the fields of the JSON summary and of ``Result.extra`` with their units,
  from ``conformal.schema.markdown``.
* :func:`cli_markdown`: every command and option of ``conformal`` from the argparse parser
  (``conformal.cli.build_parser``).
* :func:`api_pages`: one page per module group of the package, each an ``automodule`` directive
  (the text comes from the numpydoc docstrings through autodoc and napoleon).
"""
from __future__ import annotations

import argparse
import importlib
import pkgutil
from pathlib import Path

# --------------------------------------------------------------------------------------- scene keys


def scene_keys_markdown() -> str:
    """The scene keys as Markdown tables (one per TOML section), from the model registry.

    The text is :func:`conformal.scene.reference_markdown` (sections from the scene's dataclasses,
    ``[model]`` and each theory's options from :mod:`conformal.registry`); this page only adds its
    title and where it comes from.
    """
    from conformal import scene

    body = scene.reference_markdown().split("\n", 1)[1]          # drop its own title
    return "\n".join(["# Scene keys (generated)", "",
                      "Generated from the model registry and the scene layer of the package when the "
                      "documentation is built (`conformal.scene.reference_markdown`). Units: mm, N, N/mm², "
                      "rad; a key that is not listed is refused with the closest known name. A `--` default "
                      "means: not set (the key is optional or one of a set of alternatives; see "
                      "[Scene files](../scene-files.md)).", "", body])


# ------------------------------------------------------------------------------------ result fields


def schema_markdown() -> str:
    """The result fields (JSON summary and ``Result.extra``) as Markdown tables, from the schema.

    The tables are :func:`conformal.schema.markdown`; this page adds its title and where it comes
    from.
    """
    from conformal import schema

    body = schema.markdown().split("\n", 1)[1]                  # drop its own title
    return "\n".join(["# Result fields (generated)", "",
                      "Generated from `conformal/schema.py` when the documentation is built "
                      "(`conformal.schema.markdown`): every field of the JSON summary of `conformal solve` "
                      "(`Result.to_dict()`) and every `Result.extra` key, with its unit and the models that "
                      "write it. `tests/unit/test_schema.py` fails when a model writes a field that is not listed "
                      "here. See [Models](../models.md).", "", body])


# ----------------------------------------------------------------------------------------- the CLI


def _cell(text: str) -> str:
    return str(text).replace("|", "\\|").replace("\n", " ")


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
    files = {"scene_keys.md": scene_keys_markdown(), "schema.md": schema_markdown(), "cli.md": cli_markdown(),
             **api_pages()}
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


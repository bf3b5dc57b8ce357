"""Read the package's plain-text docstring conventions as reStructuredText.

The docstrings are written to be read in a terminal (``help()``): numpydoc sections where a
function has parameters, and elsewhere four plain-text habits that reStructuredText reads
differently:

* ``|x|`` for an absolute value or a norm (reST: a substitution reference),
* field lists ``name : meaning`` line after line, continuation lines indented (reST: a definition
  list that must be separated from what follows by a blank line),
* a bullet list right after its introducing line,
* an indented block (an equation, a TOML example) after a line ending with one colon (reST: ``::``).

:func:`rest_lines` rewrites those four (escapes the bars, inserts the blank lines, marks the verbatim blocks), leaving
literal blocks, doctests, tables and inline literals alone.  It runs on every docstring autodoc
reads (``autodoc-process-docstring``), after napoleon has turned the numpydoc sections into
fields, so that the build can treat every remaining markup problem as an error.
"""
from __future__ import annotations

import re

_TERM = re.compile(r"^\s*[A-Za-z_][\w.()\[\]']*(\s*,\s*[A-Za-z_][\w.()\[\]']*)*\s+:\s+\S")
_BULLET = re.compile(r"^\s*[*\-+] \S")
_TABLE = re.compile(r"^\s*(\+[-=+]+\+\s*$|\|.*\|\s*$|=+\s+=)")


def _indent(line: str) -> int:
    return len(line) - len(line.lstrip())


def _escape_bars(line: str) -> str:
    """``|`` outside inline literals and roles becomes ``\\|``."""
    if "|" not in line or _TABLE.match(line):
        return line
    parts = re.split(r"(``.*?``|`[^`]*`)", line)
    return "".join(p if p.startswith("`") else re.sub(r"(?<!\\)\|", r"\\|", p) for p in parts)


def _introduces_verbatim(lines: list[str], k: int) -> bool:
    """A prose line ending with one colon and followed by a more indented block (an equation, a
    TOML or code example): plain text's way to show verbatim text, reST's ``::``."""
    line = lines[k]
    stripped = line.strip()
    if (not stripped.endswith(":") or stripped.endswith("::") or stripped.startswith(":") or _TERM.match(line)
            or _BULLET.match(line)):
        return False
    nxt = next((x for x in lines[k + 1:] if x.strip()), None)
    return nxt is not None and _indent(nxt) > _indent(line) and not _BULLET.match(nxt)


def rest_lines(lines: list[str]) -> list[str]:
    """The docstring lines with the plain-text habits above made valid reStructuredText.

    >>> rest_lines(["Intro.", "a : first", "b, c : second", "    continued", "Text |x|."])
    ['Intro.', '', 'a : first', '', 'b, c : second', '    continued', '', 'Text \\\\|x\\\\|.']
    >>> rest_lines(["The equation:", "    y = |x|", "Back."])
    ['The equation::', '', '    y = |x|', '', 'Back.']
    """
    out: list[str] = []
    literal_indent = None          # inside a literal block (after "::") or a directive
    doctest = False                # inside a doctest block (ends at a blank line)
    item_indent = None             # inside a "term : meaning" item
    table = False                  # inside a simple table (from a ``=== ===`` border to a blank line)
    for k, line in enumerate(lines):
        stripped = line.strip()
        ind = _indent(line)
        table = (table and bool(stripped)) or bool(re.match(r"^\s*=+\s+=+[\s=]*$", line))
        if table:
            out.append(line)
            continue
        if doctest:
            doctest = bool(stripped)
            out.append(line)
            continue
        if literal_indent is not None:
            if stripped and ind <= literal_indent and not stripped.startswith(">>>"):
                literal_indent = None
                if out and out[-1].strip():
                    out.append("")
            else:
                out.append(line)
                continue
        if stripped.startswith(">>>"):
            doctest = True
            if out and out[-1].strip():
                out.append("")
            out.append(line)
            continue
        if stripped.startswith(".. "):
            literal_indent = ind
            out.append(line)
            continue
        prev = out[-1] if out else ""
        if stripped and prev.strip():
            starts_item = bool(_TERM.match(line)) and not stripped.startswith(":")
            starts_bullet = bool(_BULLET.match(line)) and not _BULLET.match(prev) and _indent(prev) <= ind
            ends_item = item_indent is not None and ind <= item_indent and _indent(prev) > item_indent
            if starts_item or ends_item or (starts_bullet and not prev.rstrip().endswith(",")):
                out.append("")
        if stripped:
            item_indent = ind if _TERM.match(line) and not stripped.startswith(":") else (
                item_indent if item_indent is not None and ind > item_indent else None)
        if _introduces_verbatim(lines, k):
            out += [_escape_bars(line) + ":", ""]
            literal_indent = ind
            continue
        out.append(_escape_bars(line))
        if stripped.endswith("::"):
            literal_indent = ind
    return out


def _process(app, what, name, obj, options, lines):
    lines[:] = rest_lines(lines)


def setup(app):
    app.setup_extension("sphinx.ext.napoleon")
    app.connect("autodoc-process-docstring", _process, priority=600)   # after napoleon (500)
    return {"version": "1", "parallel_read_safe": True, "parallel_write_safe": True}

"""CONTACT's free-format input lines (user guide, "Specification of the input file <experim>.inp").

Rules implemented here: ``%`` starts a comment up to the end of the line; empty and comment-only
lines are skipped; values are separated by blanks and/or commas; a group of values may continue on
the next lines, and the remaining text on the line with a group's last value is ignored (free
comments); optional values ``{...}`` must stand on the line of the last mandatory value; strings
are in single quotes; angles take a postfix ``d`` (degrees) or ``r`` (radians, the default);
logicals are T/t/F/f.  Control words are integers whose digits are read right-aligned (``22020``
for the six digits LDCMZE gives L = 0).

>>> d = Deck("x.inp", " 3 MODULE\\n  203000  P-B-T-N-F-S\\n 0.1, 2e-3 % c\\n  4 5  text\\n 90d\\n 'a b.prr'")
>>> d.ints(1, "module"), d.digits("PBTNFS")
([3], {'P': 2, 'B': 0, 'T': 3, 'N': 0, 'F': 0, 'S': 0})
>>> d.reals(4, "numbers"), d.reals(1, "angle", angle=True)
([0.1, 0.002, 4.0, 5.0], [1.5707963267948966])
>>> d.string("file"), parse_real(".1-07"), parse_real("1.5D+2")
('a b.prr', 1e-08, 150.0)
"""
from __future__ import annotations

import math
import re
from dataclasses import dataclass

from conformal.errors import InputError

_NUMBER = re.compile(r"^[+-]?(\d+\.?\d*|\.\d+)([eEdD][+-]?\d+|[+-]\d+)?([dDrR])?$")


@dataclass(frozen=True)
class Line:
    number: int          # 1-based line number in the file
    tokens: tuple        # the values' text (strings without their quotes, marked by a leading ')


def _split(text: str) -> list[str]:
    """Tokens of one line without its comment: quoted strings kept whole (with a leading ')."""
    out, k, n = [], 0, len(text)
    while k < n:
        c = text[k]
        if c in " \t,\r":
            k += 1
        elif c == "'":
            end = text.find("'", k + 1)
            if end < 0:
                end = n
            out.append("'" + text[k + 1:end])
            k = end + 1
        else:
            j = k
            while j < n and text[j] not in " \t,'\r":
                j += 1
            out.append(text[k:j])
            k = j
    return out


def parse_real(tok: str, *, angle: bool = False) -> float | None:
    """A real number of CONTACT's input (Fortran exponents d/D allowed; ``angle``: a postfix d for
    degrees, r for radians), None if ``tok`` is not one."""
    m = _NUMBER.match(tok)
    if not m:
        return None
    mant, expo, post = m.groups()
    if post and not angle and post in "dD" and not expo:
        return None
    if post and not angle and post in "rR":
        return None
    if expo and expo[0] in "+-":      # Fortran's exponent without a letter: .1-07
        expo = "e" + expo
    v = float(mant + (("e" + expo[1:]) if expo else ""))
    if tok.startswith("-"):
        v = -v
    if post and post in "dD":
        v = math.radians(v)
    return v


class Deck:
    """A cursor over the value lines of one input file."""

    def __init__(self, name: str, text: str):
        self.name = name
        self.lines: list[Line] = []
        for k, raw in enumerate(text.splitlines(), start=1):
            body = raw.split("%", 1)[0] if "'" not in raw else _strip_comment_quoted(raw)
            toks = _split(body)
            if toks:
                self.lines.append(Line(k, tuple(toks)))
        self.pos = 0

    # ------------------------------------------------------------------ primitives
    @property
    def at_end(self) -> bool:
        return self.pos >= len(self.lines)

    @property
    def line_number(self) -> int:
        return self.lines[min(self.pos, len(self.lines) - 1)].number if self.lines else 0

    def error(self, what: str, msg: str, line: int | None = None) -> InputError:
        return InputError(f"{self.name}, line {line or self.line_number}: {what}: {msg}")

    def _next_line(self, what: str) -> Line:
        if self.at_end:
            raise InputError(f"{self.name}: {what}: unexpected end of file")
        ln = self.lines[self.pos]
        self.pos += 1
        return ln

    def _group(self, n: int, what: str, conv, optional: int = 0) -> list:
        """n mandatory values (possibly over several lines) and up to ``optional`` more on the line
        of the last mandatory value; the rest of that line is ignored."""
        vals: list = []
        while len(vals) < n:
            ln = self._next_line(what)
            got = []
            for tok in ln.tokens:
                v = conv(tok)
                if v is None:
                    break
                got.append(v)
            if not got:
                raise self.error(what, f"expected {n - len(vals)} more value(s), got {' '.join(ln.tokens)[:60]!r}",
                                 ln.number)
            room = n - len(vals)
            vals.extend(got[:room + optional])
        return vals

    # ------------------------------------------------------------------ typed groups
    def ints(self, n: int, what: str, optional: int = 0) -> list[int]:
        def conv(tok):
            return int(tok) if re.fullmatch(r"[+-]?\d+", tok) else None
        return self._group(n, what, conv, optional)

    def reals(self, n: int, what: str, optional: int = 0, angle: bool = False) -> list[float]:
        return self._group(n, what, lambda t: parse_real(t, angle=angle), optional)

    def mixed(self, kinds: str, what: str, optional: str = "") -> list:
        """Values of the given kinds on one group: i integer, r real, a angle, s string, l logical."""
        convs = {"i": lambda t: int(t) if re.fullmatch(r"[+-]?\d+", t) else None,
                 "r": parse_real, "a": lambda t: parse_real(t, angle=True),
                 "s": lambda t: t[1:] if t.startswith("'") else None,
                 "l": lambda t: {"t": True, "f": False}.get(t.lower()) if len(t) == 1 else None}
        vals: list = []
        kinds_all = kinds + optional
        while len(vals) < len(kinds):
            ln = self._next_line(what)
            got = 0
            for tok in ln.tokens:
                if len(vals) >= len(kinds_all) or (len(vals) >= len(kinds) and got == 0):
                    break
                v = convs[kinds_all[len(vals)]](tok)
                if v is None:
                    break
                vals.append(v)
                got += 1
            if got == 0:
                raise self.error(what, f"expected a value of kind {kinds_all[len(vals)]!r}, got "
                                       f"{' '.join(ln.tokens)[:60]!r}", ln.number)
        return vals

    def string(self, what: str) -> str:
        ln = self._next_line(what)
        if not ln.tokens[0].startswith("'"):
            raise self.error(what, f"expected a quoted file name, got {ln.tokens[0]!r}", ln.number)
        return ln.tokens[0][1:]

    def digits(self, letters: str, what: str | None = None, optional: str = "") -> dict[str, int]:
        """A control word: the digits of one integer, right-aligned onto ``letters`` (missing leading
        digits are 0); ``optional`` letters follow as separate single-digit integers on the line."""
        what = what or letters
        ln = self._next_line(what)
        tok = ln.tokens[0]
        if not re.fullmatch(r"\d+", tok):
            raise self.error(what, f"expected the control word {letters}, got {tok!r}", ln.number)
        if len(tok) > len(letters):
            raise self.error(what, f"control word {tok!r} has more digits than {letters}", ln.number)
        tok = tok.rjust(len(letters), "0")
        out = {c: int(v) for c, v in zip(letters, tok)}
        for c, t in zip(optional, ln.tokens[1:]):
            if not re.fullmatch(r"\d", t):
                break
            out[c] = int(t)
        return out


def _strip_comment_quoted(raw: str) -> str:
    """The line up to its first % outside single quotes."""
    inq = False
    for k, c in enumerate(raw):
        if c == "'":
            inq = not inq
        elif c == "%" and not inq:
            return raw[:k]
    return raw

"""The README and the documentation pages: size, the two commands, links, generated reference.

The Sphinx build itself (warnings as errors) runs in CI (.ci/run); these checks run in the fast lane
without Sphinx.
"""
import re
import sys

import pytest
from _paths import ROOT

DOCS = ROOT / "docs"
LINK = re.compile(r"\]\(([^)#\s]+)(#[^)\s]*)?\)")


def pages():
    return [ROOT / "README.md"] + sorted(p for p in DOCS.rglob("*.md")
                                         if "_build" not in p.parts and "_generated" not in p.parts
                                         and "incoming" not in p.parts)


def test_readme_is_short_and_starts_with_the_two_commands():
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    assert len(text.splitlines()) <= 200
    block = re.search(r"```bash\n(.*?)```", text, re.S).group(1).splitlines()
    assert block == ['pip install -e . && conformal demo', 'pip install -e ".[test]" && python -m pytest']
    ci = (ROOT / ".ci" / "run").read_text(encoding="utf-8")
    assert 'pip install --quiet -e ".[test]" && python -m pytest\n' in ci     # the README's test command
    assert "python -m sphinx -W" in ci


@pytest.mark.parametrize("page", pages(), ids=lambda p: str(p.relative_to(ROOT)))
def test_relative_links_resolve(page):
    text = page.read_text(encoding="utf-8")
    text = re.sub(r"```.*?```", "", text, flags=re.S)                       # code blocks hold no links
    missing = [m.group(1) for m in LINK.finditer(text)
               if not re.match(r"[a-z]+:", m.group(1)) and not (page.parent / m.group(1)).exists()
               and "_generated" not in m.group(1)]
    assert not missing, f"{page.name}: broken links {missing}"


def _generated():
    """The docs' reference generators (docs/_ext/generated.py), imported without leaving docs/_ext on sys.path."""
    sys.path.insert(0, str(DOCS / "_ext"))
    try:
        import generated
    finally:
        sys.path.remove(str(DOCS / "_ext"))
    return generated


def test_scene_key_reference_covers_every_section_field():
    generated = _generated()
    import dataclasses
    from conformal import scene, specs

    text = generated.scene_keys_markdown()
    for cls in (scene.WheelRailGeometry, scene.Load, scene.GridSpec, specs.Kinematics, specs.ModelSpec,
                specs.HistoryStep):
        for f in dataclasses.fields(cls):
            if f.name not in ("kind", "options"):
                assert f"| `{f.name}` |" in text, (cls.__name__, f.name)
    for key in list(scene.MODEL_OPTIONS) + list(scene.THEORIES):
        # the flat keys fe_<key> / fec_<key> are listed by their nested names ([model.fe] <key>)
        nested = key.split("_", 1)[1] if key in scene.MODEL_OPTIONS and key.startswith(("fe_", "fec_")) else key
        assert f"`{nested}`" in text, key
    assert "### [model.fe]" in text and "### [model.fe_contact]" in text and "flat spelling: `[model] fe_<key>`" in text
    # a default in the table is the default a scene gets
    row = re.search(r"\| `gauge_height` \| number \| (\S+) \| mm \|", text)
    assert float(row.group(1)) == scene.WheelRailGeometry().gauge_height


def test_cli_reference_lists_every_command():
    generated = _generated()
    text = generated.cli_markdown()
    for command in ("solve", "sweep", "demo", "precompute", "cache", "table build", "table refine", "table info",
                    "simulate", "stability", "inp", "stresses"):
        assert f"## `conformal {command}`" in text
    assert "`--allow-unconverged`" in text


def test_result_field_reference_lists_every_field():
    generated = _generated()
    from conformal import schema

    text = generated.schema_markdown()
    assert text.startswith("# Result fields (generated)")
    for key, field in {**schema.SUMMARY, **schema.EXTRA}.items():
        assert f"| `{key}` | {field.unit} |" in text, key
    assert "| `FZ_track` | N |" in text

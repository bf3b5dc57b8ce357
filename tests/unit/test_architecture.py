"""The import architecture: the layers contract of pyproject.toml ([tool.importlinter], checked by
import-linter) and no import cycle between modules, counting imports inside functions."""
import sys

import pytest
from _paths import ROOT



def declared_imports() -> list[str]:
    """The modules the package's model declarations name (``Model(..., solve="module:function")``):
    conformal.models imports them by name (importlib), which no import graph sees by itself."""
    from conformal.registry import MODELS

    return sorted({m.solve_module for m in MODELS if m.solve_module})


def _with_imports_of_models(build_graph, modules):
    """grimp's build_graph with ``conformal.models -> module`` added for each of ``modules``."""
    def build(*args, **kwargs):
        graph = build_graph(*args, **kwargs)
        for module in modules:
            graph.add_import(importer="conformal.models", imported=module)
        return graph
    return build


def _lint(monkeypatch, modules) -> int:
    """import-linter's check of pyproject's contracts, the declared model modules counted as imports."""
    grimp = pytest.importorskip("grimp")
    pytest.importorskip("importlinter")
    from importlinter.cli import lint_imports

    monkeypatch.chdir(ROOT)
    monkeypatch.setattr(grimp, "build_graph", _with_imports_of_models(grimp.build_graph, modules))
    return lint_imports(config_filename=str(ROOT / "pyproject.toml"), no_cache=True)


def test_import_contracts_are_kept(monkeypatch):
    """The layers of pyproject.toml, with conformal.models importing every module a model declares."""
    modules = declared_imports()
    assert "conformal.tables.model" in modules and "conformal.theories.hertz" in modules
    assert _lint(monkeypatch, modules) == 0


def test_the_contract_refuses_a_model_declared_above_conformal_models(monkeypatch, capsys):
    """A declaration naming a module of a higher layer (here the CLI) breaks the layers contract."""
    assert _lint(monkeypatch, declared_imports() + ["conformal.cli"]) != 0
    assert "conformal.models -> conformal.cli" in capsys.readouterr().out


def _cycles(graph) -> list[list[str]]:
    """Strongly connected components of more than one module (Tarjan, iterative)."""
    modules = sorted(graph.modules)
    adj = {m: sorted(graph.find_modules_directly_imported_by(m)) for m in modules}
    index, low, on, stack, out, counter = {}, {}, set(), [], [], [0]
    for root in modules:
        if root in index:
            continue
        work = [(root, iter(adj[root]))]
        index[root] = low[root] = counter[0]
        counter[0] += 1
        stack.append(root)
        on.add(root)
        while work:
            v, it = work[-1]
            for w in it:
                if w not in index:
                    index[w] = low[w] = counter[0]
                    counter[0] += 1
                    stack.append(w)
                    on.add(w)
                    work.append((w, iter(adj[w])))
                    break
                if w in on:
                    low[v] = min(low[v], index[w])
            else:
                work.pop()
                if work:
                    low[work[-1][0]] = min(low[work[-1][0]], low[v])
                if low[v] == index[v]:
                    comp = []
                    while True:
                        w = stack.pop()
                        on.discard(w)
                        comp.append(w)
                        if w == v:
                            break
                    if len(comp) > 1:
                        out.append(sorted(comp))
    return out


def test_no_import_cycles_counting_imports_in_functions():
    grimp = pytest.importorskip("grimp")
    sys.path.insert(0, str(ROOT))
    graph = _with_imports_of_models(grimp.build_graph, declared_imports())("conformal", include_external_packages=False)
    assert _cycles(graph) == []


def test_the_cycle_finder_finds_a_cycle():
    class G:
        modules = {"a", "b", "c", "d"}

        @staticmethod
        def find_modules_directly_imported_by(m):
            return {"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}[m]

    assert _cycles(G) == [["a", "b", "c"]]


# ----------------------------------------------------------------------------- the influence-operator protocol
#: the operator classes; solvers receive them from conformal.influence.operator.build_operator
OPERATOR_CLASSES = {"HalfSpaceInfluence", "CurvedInfluence", "LineInfluence", "FileInfluence"}


def _protocol_violations(source: str, name: str) -> list[str]:
    """Where a solver module reaches past the operator protocol: an operator class named (isinstance,
    construction, import), a private name imported from another module, or a private attribute of
    anything but ``self``/``cls`` (e.g. ``op._forward``, ``exact._result``)."""
    import ast

    out = []
    for node in ast.walk(ast.parse(source)):
        where = f"{name}:{getattr(node, 'lineno', '?')}"
        if isinstance(node, ast.ImportFrom):
            for a in node.names:
                if a.name.startswith("_") or a.name in OPERATOR_CLASSES:
                    out.append(f"{where} imports {a.name} from {node.module}")
        elif isinstance(node, ast.Name) and node.id in OPERATOR_CLASSES:
            out.append(f"{where} names {node.id}")
        elif isinstance(node, ast.Attribute):
            if node.attr in OPERATOR_CLASSES:
                out.append(f"{where} names {node.attr}")
            elif node.attr.startswith("_") and not node.attr.startswith("__"):
                base = node.value
                if not (isinstance(base, ast.Name) and base.id in ("self", "cls")):
                    out.append(f"{where} reads the private {ast.unparse(node)}")
    return out


def test_solvers_use_influence_operators_only_through_the_protocol():
    files = sorted((ROOT / "conformal" / "solvers").glob("*.py"))
    assert len(files) >= 8
    found = [v for f in files for v in _protocol_violations(f.read_text(), f.name)]
    assert found == []


def test_the_protocol_check_sees_isinstance_private_calls_and_private_imports():
    src = ("from conformal.influence.halfspace import HalfSpaceInfluence\n"
           "from conformal.solvers.exact import _result\n"
           "def f(op, exact):\n"
           "    if isinstance(op, HalfSpaceInfluence):\n"
           "        return op._forward(1)\n"
           "    return exact._tangential(self._ok)\n")
    found = _protocol_violations(src, "m.py")
    assert any("imports HalfSpaceInfluence" in v for v in found)
    assert any("imports _result" in v for v in found)
    assert any("m.py:4 names HalfSpaceInfluence" in v for v in found)
    assert any("op._forward" in v for v in found)
    assert any("exact._tangential" in v for v in found)
    assert not any("self._ok" in v for v in found)


def test_every_operator_class_has_every_protocol_member():
    from conformal.influence.contact_file import FileInfluence
    from conformal.influence.curved import CurvedInfluence
    from conformal.influence.halfplane import LineInfluence
    from conformal.influence.halfspace import HalfSpaceInfluence
    from conformal.influence.operator import PROTOCOL_MEMBERS, InfluenceOperator

    declared = {n for n in vars(InfluenceOperator) if not n.startswith("_")} | set(InfluenceOperator.__annotations__)
    assert declared == set(PROTOCOL_MEMBERS)
    for cls in (HalfSpaceInfluence, CurvedInfluence, LineInfluence, FileInfluence):
        fields = getattr(cls, "__dataclass_fields__", {})
        missing = [m for m in PROTOCOL_MEMBERS if not (hasattr(cls, m) or m in fields)]
        assert missing == [], f"{cls.__name__} lacks {missing}"

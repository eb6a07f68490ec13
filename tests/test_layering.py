"""Imports run one way (docs/architecture.md): the layers contract of pyproject.toml holds, and no
module imports another module's private (single leading underscore) names."""
import ast
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
LINT_IMPORTS = Path(sys.executable).parent / "lint-imports"
PACKAGES = sorted(p.name for p in ROOT.iterdir() if (p / "__init__.py").is_file() and p.name != "tests")


def _private(name: str) -> bool:
    return name.startswith("_") and not name.startswith("__")


def private_imports(source: str, where: str = "<source>") -> list[str]:
    """Each ``from m import _x``, ``import m._x`` and ``m._x`` on an imported name ``m``, as 'where:line: text'."""
    tree = ast.parse(source)
    imported, out = set(), []
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom):
            for alias in node.names:
                if _private(alias.name):
                    out.append(f"{where}:{node.lineno}: from {'.' * node.level}{node.module or ''} import {alias.name}")
                imported.add(alias.asname or alias.name)
        elif isinstance(node, ast.Import):
            for alias in node.names:
                if any(_private(part) for part in alias.name.split(".")):
                    out.append(f"{where}:{node.lineno}: import {alias.name}")
                imported.add(alias.asname or alias.name.split(".")[0])
    for node in ast.walk(tree):
        if (isinstance(node, ast.Attribute) and _private(node.attr) and isinstance(node.value, ast.Name)
                and node.value.id in imported):
            out.append(f"{where}:{node.lineno}: {node.value.id}.{node.attr}")
    return out


def test_the_scan_names_a_private_import_and_a_private_name_of_an_imported_module():
    source = "from .fits import _helper\nimport calibrate.curves_integration as r2\nfrom claims import table\n" \
             "x = r2._budget\ny = table._per_seed(1)\nz = self._own\n"
    assert private_imports(source, "m.py") == ["m.py:1: from .fits import _helper", "m.py:4: r2._budget",
                                               "m.py:5: table._per_seed"]


def test_no_module_imports_a_private_name_of_another():
    files = [f for pkg in PACKAGES for f in sorted((ROOT / pkg).rglob("*.py"))]
    files += sorted((ROOT / "workflow" / "scripts").glob("*.py"))
    assert len(files) > 50
    found = [line for f in files for line in private_imports(f.read_text(), str(f.relative_to(ROOT)))]
    assert found == []


def lint_imports(cwd) -> subprocess.CompletedProcess:
    return subprocess.run([str(LINT_IMPORTS), "--config", str(ROOT / "pyproject.toml"), "--no-cache"],
                          cwd=cwd, capture_output=True, text=True, timeout=300)


def test_the_packages_keep_the_layers_contract():
    result = lint_imports(ROOT)
    assert result.returncode == 0, result.stdout + result.stderr
    assert "1 kept, 0 broken" in result.stdout


def test_the_contract_refuses_an_import_from_a_later_stage(tmp_path):
    """The same contract on a tree of empty packages where calibrate imports claims: broken, and named."""
    for pkg in PACKAGES:
        (tmp_path / pkg).mkdir()
        (tmp_path / pkg / "__init__.py").write_text("")
    (tmp_path / "calibrate" / "__init__.py").write_text("import claims\n")
    result = lint_imports(tmp_path)
    assert result.returncode == 1, result.stdout + result.stderr
    assert "calibrate is not allowed to import claims" in result.stdout

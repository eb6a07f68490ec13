"""The couplings the import contract cannot see (docs/architecture.md): import-linter reads importable
packages only, so the workflow's imports (Snakefile, workflow/rules/*.smk) and the yade_scripts files
that campaign.scene_spec loads through importlib are checked here, against what the docs say."""
import ast
import re
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = sorted(p.name for p in ROOT.iterdir() if (p / "__init__.py").is_file() and p.name != "tests")
ARCHITECTURE = ROOT / "docs" / "architecture.md"
LOADER = ROOT / "campaign" / "scene_spec.py"


def package_row(first_cell: str) -> str:
    """The row of docs/architecture.md's package table whose first cell starts with ``first_cell``."""
    rows = [line for line in ARCHITECTURE.read_text().splitlines() if line.startswith(f"| {first_cell}")]
    assert len(rows) == 1, first_cell
    return rows[0]


def workflow_imports() -> dict[str, set[str]]:
    """The project's packages the workflow imports -> the files (Snakefile, rule files) that import each."""
    out: dict[str, set[str]] = {}
    for path in [ROOT / "Snakefile", *sorted((ROOT / "workflow" / "rules").glob("*.smk"))]:
        for m in re.finditer(r"^\s*(?:from|import)\s+([A-Za-z_][\w]*)", path.read_text(), re.MULTILINE):
            if m[1] in PACKAGES:
                out.setdefault(m[1], set()).add(path.name)
    return out


def test_the_workflow_imports_the_packages_its_row_in_docs_architecture_names():
    documented = set(re.findall(r"`(\w+)`", package_row("`Snakefile`").split("imports", 1)[1])) & set(PACKAGES)
    actual = workflow_imports()
    assert set(actual) == documented
    assert "dem.smk" in actual["dem_study"]    # the DEM rules' one upward reach, named in the docs


def loaded_yade_scripts() -> set[str]:
    """The yade_scripts files the packages load by name through ``campaign.scene_spec``."""
    names = {"scene"}   # scene_spec.scene_module
    for pkg in PACKAGES:
        for path in (ROOT / pkg).rglob("*.py"):
            names |= set(re.findall(r"yade_scripts_module\(\"(\w+)\"", path.read_text()))
    return names


def test_only_campaign_scene_spec_loads_code_from_a_file():
    loaders = sorted(str(p.relative_to(ROOT)) for pkg in PACKAGES for p in (ROOT / pkg).rglob("*.py")
                     if re.search(r"\bimportlib\b|\brunpy\b|\bexec\(", p.read_text()))
    assert loaders == [str(LOADER.relative_to(ROOT))]


def test_the_yade_scripts_files_loaded_import_only_the_standard_library_and_the_docs_name_them():
    names = loaded_yade_scripts()
    assert names >= {"scene", "stagelock"}
    for name in names:
        tree = ast.parse((ROOT / "yade_scripts" / f"{name}.py").read_text())
        tops = {a.name.split(".")[0] for n in ast.walk(tree) if isinstance(n, ast.Import) for a in n.names}
        tops |= {n.module.split(".")[0] for n in ast.walk(tree) if isinstance(n, ast.ImportFrom) and n.level == 0}
        assert tops - {"__future__"} <= set(sys.stdlib_module_names), name
        assert f"`yade_scripts/{name}.py`" in package_row("`campaign/`")

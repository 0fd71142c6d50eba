"""labkit.vision's three packages (ADR 0034), read from the source (tests/architecture/
import_rules.py): ``shared`` imports neither pipeline, and neither pipeline imports the other;
every module of labkit.vision sits in one of the three (apart from the package's face)."""

from __future__ import annotations

from pathlib import Path

from .import_rules import all_imports, modules_of

LABKIT = Path(__file__).resolve().parents[2] / "labkit"
PACKAGES = ("shared", "laser", "strobe")
#: what each package of labkit.vision may import from the others
MAY_IMPORT = {"shared": set(), "laser": {"shared"}, "strobe": {"shared"}}


def _package(module: str) -> str | None:
    """``labkit.vision.laser.trace`` -> ``laser``; None outside labkit.vision's packages."""
    parts = module.split(".")
    return parts[2] if len(parts) > 2 and parts[:2] == ["labkit", "vision"] else None


def vision_violations(root: Path) -> list[str]:
    """Imports between labkit.vision's packages that ``MAY_IMPORT`` does not allow."""
    found = []
    for imp in all_imports(root):
        source, target = _package(imp.module), _package(imp.target)
        if source and target and source != target and target not in MAY_IMPORT.get(source, set()):
            found.append(f"{imp.module}:{imp.line} imports {imp.target} ({source} may not import {target})")
    return found


def test_the_vision_packages_import_only_shared():
    found = vision_violations(LABKIT)
    assert not found, "\n  ".join(["imports across labkit.vision's pipelines:", *found])


def test_every_vision_module_sits_in_a_package():
    vision = [m for m in modules_of(LABKIT) if m.startswith("labkit.vision.")]
    loose = [m for m in vision if _package(m) not in PACKAGES]
    assert len(vision) > 30 and loose == []


def test_the_rule_sees_a_strobe_module_importing_the_laser(tmp_path):
    root = tmp_path / "labkit"
    for package in PACKAGES:
        (root / "vision" / package).mkdir(parents=True)
        (root / "vision" / package / "__init__.py").write_text("")
    (root / "__init__.py").write_text("")
    (root / "vision" / "__init__.py").write_text("")
    (root / "vision" / "laser" / "fit.py").write_text("LIMIT = 1\n")
    (root / "vision" / "shared" / "curves.py").write_text("LIMIT = 2\n")
    (root / "vision" / "strobe" / "analyse.py").write_text(
        "from labkit.vision.shared.curves import LIMIT\n\n\n"
        "def f():\n    from labkit.vision.laser.fit import LIMIT\n")
    assert vision_violations(root) == [
        "labkit.vision.strobe.analyse:5 imports labkit.vision.laser.fit (strobe may not import laser)"]

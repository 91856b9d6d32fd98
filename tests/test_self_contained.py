"""copi runs from a clone with nothing beside it: no file of the project reads data from
outside the repository (the maps ship in the package, the reference data in tests/data)."""

from __future__ import annotations

from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
OUTSIDE = ("../shared", "shared/data", 'parents[3] / "shared"', "parent / \"shared\"")


def test_nothing_reads_beside_the_repository() -> None:
    places = [ROOT / "Makefile", ROOT / ".ci" / "run", ROOT / "README.md", ROOT / "pyproject.toml"]
    for folder in ("src", "tests", "benchmarks", "studies", "tools", "docs"):
        places += [p for p in (ROOT / folder).rglob("*") if p.suffix in (".py", ".md", ".toml")]
    offenders = []
    for p in places:
        if p == Path(__file__).resolve() or "data" in p.relative_to(ROOT).parts[:2]:
            continue
        text = p.read_text(encoding="utf-8", errors="replace")
        offenders += [f"{p.relative_to(ROOT)}: {o}" for o in OUTSIDE if o in text]
    assert offenders == []


def test_the_reference_data_is_in_the_repository() -> None:
    data = ROOT / "tests" / "data"
    assert len(list(data.rglob("*.scen"))) == 13  # 12 Moving AI files and the mesh's
    assert (data / "polygons" / "extremitypathfinder" / "cases.json").is_file()
    assert (data / "polygons" / "ironharvest_mesh" / "scene_mp_2p_01.mesh").is_file()
    assert (data / "homicidal_chauffeur" / "critical_beta.csv").is_file()
    for folder in ("movingai", "polygons"):
        assert (data / folder / "PROVENANCE.tsv").is_file()

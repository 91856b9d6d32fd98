"""The documentation: short README, generated blocks up to date, every link there, and
the tutorials' code runs as written."""

from __future__ import annotations

import importlib.util
import re
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
TUTORIALS = sorted((DOCS / "tutorials").glob("*.md"))


def _tool():
    spec = importlib.util.spec_from_file_location("update_docs", ROOT / "tools" / "update_docs.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _python_blocks(path: Path) -> list[str]:
    return re.findall(r"```python\n(.*?)```", path.read_text(), re.S)


def test_the_readme_is_short_and_its_links_exist() -> None:
    text = (ROOT / "README.md").read_text()
    assert len(text.splitlines()) <= 200
    links = re.findall(r"\]\(([^)#]+)(?:#[^)]*)?\)", text)
    assert links
    missing = [x for x in links if not x.startswith("http") and not (ROOT / x).exists()]
    assert not missing, missing


@pytest.mark.parametrize("page", _tool().PAGES)
def test_generated_blocks_are_what_the_tool_writes(page: str) -> None:
    """The methods table and the headline results are generated (never typed): a page
    that differs from what ``python tools/update_docs.py`` writes fails here."""
    path = ROOT / page
    assert path.read_text() == _tool().generated(path), (
        f"{page} is out of date: run python tools/update_docs.py"
    )


def test_quoted_paragraphs_are_the_sections_bold_ones(tmp_path: Path) -> None:
    """The README's family-by-family gaps are the ceilings page's own paragraphs: a
    stale block is rewritten, every family is there, the page's other prose is not."""
    tool = _tool()
    page = tmp_path / "page.md"
    page.write_text("<!-- quote-text ceilings.md#How much of the gap copi closes -->\n"
                    "stale\n<!-- /quote-text -->\n")  # fmt: skip
    text = tool.generated(page)
    assert "stale" not in text and "The gap is the oracle's success" not in text
    for family in ("star", "polygon", "indoor", "maps", "crowd"):
        assert f"**{family}**: " in text, family
    with pytest.raises(SystemExit, match="has no heading"):
        tool.quoted_paragraphs("ceilings.md#No such section")
    # "| rows: A" keeps A's paragraph alone; a name with no paragraph is refused
    crowd = tool.quoted_paragraphs("ceilings.md#How much of the gap copi closes | rows: crowd")
    assert crowd.startswith("**crowd**: ") and "**star**" not in crowd
    with pytest.raises(SystemExit, match="no paragraph opens with a bold name of"):
        tool.quoted_paragraphs("ceilings.md#How much of the gap copi closes | rows: moon")


def test_a_results_line_that_differs_from_its_source_fails(tmp_path: Path) -> None:
    tool = _tool()
    page = tmp_path / "page.md"
    page.write_text("<!-- methods -->\nstale\n<!-- /methods -->\n")
    assert "stale" not in tool.generated(page) and "| `copi-learnt` |" in tool.generated(page)


def test_a_headline_whose_row_no_longer_holds_it_stops_the_tool(monkeypatch) -> None:
    """A README headline saying a row has more successes is written only while the row's
    *versus* cell says so: the same row asked to hold a phrase it lacks is refused."""
    tool = _tool()
    held = [r for r in tool.RESULTS if r[3]]
    assert len(held) >= 2
    for row in held:
        assert row[3] in tool.quoted_row(row[0], row[1]).splitlines()[-1]
        monkeypatch.setattr(tool, "RESULTS", [(*row[:3], "fewer successes; longer paths")])
        with pytest.raises(SystemExit, match="no longer says 'fewer successes; longer paths'"):
            tool.results_block()


@pytest.mark.parametrize("page", TUTORIALS, ids=[p.stem for p in TUTORIALS])
def test_the_tutorials_run_as_written(page: Path, tmp_path: Path, monkeypatch) -> None:
    blocks = _python_blocks(page)
    assert blocks, f"{page.name} has no Python"
    monkeypatch.chdir(tmp_path)
    namespace: dict = {"__name__": f"tutorial_{page.stem}"}
    for code in blocks:
        exec(compile(code, str(page), "exec"), namespace)  # noqa: S102


@pytest.mark.slow
@pytest.mark.parametrize("page", ["README.md", "docs/index.md"])
def test_the_quickstart_runs(page: str, tmp_path: Path, monkeypatch, capsys) -> None:
    """The quickstart learns at the preset's full scale (about a minute): in ``make bench``.
    The file it writes is the learnt preset's, as learnt; the line it prints is what
    its comments say: copi-learnt on the benchmark's indoor episode 3 at level map, run
    here again from that file (outcome, steps, path length)."""
    import dataclasses

    from copi.learning import Capabilities
    from copi.methods import PRESETS, check_preset_capabilities, make_agent
    from copi.runs import draw_episode, run_episode

    monkeypatch.chdir(tmp_path)
    (code,) = _python_blocks(ROOT / page)
    namespace: dict = {"__name__": "quickstart"}
    exec(compile(code, page, "exec"), namespace)  # noqa: S102
    printed = capsys.readouterr().out.strip().splitlines()[-1]
    caps = Capabilities.load(tmp_path / "caps-learnt.npz")
    check_preset_capabilities("learnt", caps)
    want = dataclasses.asdict(PRESETS["learnt"].learn)  # what it records of it, as asked
    learnt = {k: v for k, v in caps.params.items() if k != "workers"}
    assert learnt == {k: want[k] for k in learnt} and learnt["directions"] == 16
    assert caps.equals(namespace["caps"])
    sim = draw_episode("indoor", 3, seed=0)
    out = run_episode(make_agent("copi-learnt", caps), sim, sensing="map", max_steps=1000)
    assert printed == f"{out.outcome} {out.steps} {round(out.path_length, 1)}", printed
    outcome, steps, length = printed.split()
    assert outcome in ("success", "collision", "timeout") and 1 <= int(steps) <= 1000
    assert 0.0 < float(length) <= int(steps) + 0.05  # one agent step a step at most
    if outcome == "success":
        assert np.hypot(*(sim.position - sim.goal)) <= sim.goal_tolerance
    elif outcome == "timeout":
        assert int(steps) == 1000


def test_a_quote_is_the_generated_pages_table_and_can_keep_rows() -> None:
    tool = _tool()
    source = (DOCS / "families.md").read_text()
    table = tool.quoted_table("families.md#Statistics")
    assert table.strip() in source and table.startswith("| family |")
    star = tool.quoted_table("families.md#Statistics | rows: star")
    assert star.splitlines()[:2] == table.splitlines()[:2]
    assert [x.split("|")[1].strip() for x in star.splitlines()[2:]] == ["star"]
    for bad in ("nowhere.md#x", "families.md#No such heading", "families.md#Statistics#9",
                "families.md#Statistics | rows: nobody"):  # fmt: skip
        with pytest.raises(SystemExit):
            tool.quoted_table(bad)


def _outside_generated_blocks(text: str) -> str:
    return re.sub(r"<!-- (quote|methods|results|table)\b[^>]*-->.*?<!-- /\1 -->", "", text,
                  flags=re.S)


_WRITTEN = sorted(
    str(p.relative_to(ROOT)) for p in [ROOT / "README.md", *DOCS.rglob("*.md")]
    if "<!-- generated" not in p.read_text()[:1000]
)  # fmt: skip
"""The pages written by hand: every page but those a command writes whole (each says so
in a comment under its title, naming the command)."""


@pytest.mark.parametrize("page", _WRITTEN)
def test_no_results_table_is_typed_by_hand(page: str) -> None:
    """A table with a measured number in it (a cell that is a number, a percentage or an
    interval) lives only in a generated block, quoted from a generated page."""
    text = _outside_generated_blocks((ROOT / page).read_text())
    number = re.compile(r"^\s*\**[-+−]?\d[\d,.]*\s?%?\s*[▲▽]?\s*(\([^)]*\))?\**\s*$")
    interval = re.compile(r"\[[-+−]?\d[\d.]*, [-+−]?\d")
    typed = [line for line in text.splitlines() if line.startswith("|") and (
        interval.search(line) or any(number.match(c) for c in line.strip("|").split("|")))]
    assert not typed, f"{page} types results by hand: {typed[:3]}"

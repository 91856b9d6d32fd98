"""Write the generated blocks of the README and the docs (never typed by hand):

    python tools/update_docs.py

- between ``<!-- methods ... -->`` and ``<!-- /methods -->``: the registry's table of
  methods (:func:`copi.methods.methods_markdown`);
- between ``<!-- results ... -->`` and ``<!-- /results -->`` (README only): the headline
  rows, each quoted whole from the generated results page it names (``RESULTS`` below);
- between ``<!-- quote-text PAGE#SECTION -->`` and ``<!-- /quote-text -->``: the
  paragraphs under the heading ``SECTION`` of ``docs/PAGE`` that open with a bold name
  (``**crowd**: ...``), quoted whole (the ceilings' family-by-family gaps, the
  benchmark's words on its tables); ``| rows: A, B`` keeps the paragraphs whose bold
  name is A or B;
- between ``<!-- quote PAGE#SECTION -->`` and ``<!-- /quote -->`` (any page in ``PAGES``):
  the first table under the heading ``SECTION`` of the generated page ``docs/PAGE``
  (``PAGE#SECTION#N``: its N-th table, from 1), quoted whole; ``| rows: A, B`` after the
  section keeps only the rows whose first cell is one of the methods named (the header
  kept), so that the analysis pages never carry a results table typed by hand.

``tests/test_docs.py`` fails when a block differs from what this script would write.
"""

from __future__ import annotations

import re
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "src"))

RESULTS: list[tuple[str, str, str, str]] = [
    ("ceilings.md", "| crowd |",
     "**What is possible.** Every episode of every family is solvable by a clairvoyant; in "
     "crowds no method comes near it, and the best of them are planners over the discs' "
     "futures (copi-predictive's learnt model among them)", ""),
    ("benchmark-bounds.md#crowd", "| copi-predictive | map |",
     "**Where copi-learnt loses.** copi-predictive — the reference planner's planning over "
     "futures drawn from copi's learnt model of what moves, with no hand-written guard, at "
     "the same level — has more successes than copi-learnt (the reference of Δ) in crowds",
     "more successes"),
    ("rl.md#Like with like", "| crowd |",
     "**Against deep RL, like with like.** PPO given what copi-learnt sees at `map` (the "
     "hits the static map does not explain, stacked readings), trained in crowds for 2M "
     "steps, beside copi-predictive (learnt, no hand-written guard): in crowds the peer "
     "learnt little and missed its goal (its last column)", "**missed**"),
    ("benchmark-sensor.md#Overview", "| copi-predictive | sensor |",
     "**With no map.** At level `sensor` (its reading and the relative goal alone) "
     "copi-predictive, with no hand-written guard, has more successes than copi-learnt (▲) "
     "in polygon, indoor and maps (success in %, median excess), and none fewer than "
     "copi-learnt following a map it builds (the `mapping` strategy; in indoor 58.5 % "
     "against its 63.0, the interval holding zero)",
     "▲"),
]
"""(source page, the row's first cells, what the line says of it, a phrase the row must
hold for the line to be true): each headline is the row of a generated table whose first
cells match, quoted whole; a row that no longer holds its phrase stops the tool, so that
no headline outlives the numbers it speaks of."""


def _block(text: str, tag: str, body: str) -> str:
    pattern = re.compile(rf"(<!-- {tag}[^>]*-->\n).*?(<!-- /{tag} -->)", re.S)
    if not pattern.search(text):
        raise SystemExit(f"no <!-- {tag} --> block")
    return pattern.sub(lambda m: m.group(1) + body + m.group(2), text)


def quoted_row(page: str, first: str) -> str:
    """The row of ``docs/page`` whose first cells are ``first`` (e.g. "| crowd | map |"),
    under its table's header; ``page#section`` looks from the heading "## section" on."""
    page, _, section = page.partition("#")
    lines = (ROOT / "docs" / page).read_text().splitlines()
    if section:
        start = next((i for i, x in enumerate(lines) if x.startswith(f"## {section}")), None)
        if start is None:
            raise SystemExit(f"docs/{page}: no section {section!r}")
        lines = lines[start:]
    header: list[str] = []
    previous = ""
    for line in lines:
        if line.startswith("|") and not previous.startswith("|"):
            header = [line]
        elif line.startswith("|---"):
            header.append(line)
        elif line.startswith(first):
            return "\n".join([*header, line])
        previous = line
    raise SystemExit(f"docs/{page}: no row starting {first!r}")


def results_block() -> str:
    out = []
    for page, first, label, holds in RESULTS:
        file = page.partition("#")[0]
        row = quoted_row(page, first)
        if holds not in row.splitlines()[-1]:
            raise SystemExit(f"README headline {label[:40]!r}...: docs/{page}'s row "
                             f"{first!r} no longer says {holds!r}; reword the headline")
        out.append(f"{label} ([docs/{file}](docs/{file})):\n\n{row}\n")
    return "\n".join(out)


def _tables(lines: list[str]) -> list[list[str]]:
    tables: list[list[str]] = []
    previous = ""
    for line in lines:
        if line.startswith("|"):
            if not previous.startswith("|"):
                tables.append([])
            tables[-1].append(line)
        elif line.startswith("#") and tables:
            break  # the next heading ends the section
        previous = line
    return tables


def quoted_table(spec: str) -> str:
    """The table ``PAGE#SECTION[#N][ | rows: A, B]`` names (see the module)."""
    where, _, rows = spec.partition("|")
    page, _, section = where.strip().partition("#")
    section, _, nth = section.partition("#")
    path = ROOT / "docs" / page
    if not path.is_file():
        raise SystemExit(f"quote {spec!r}: no docs/{page}")
    lines = path.read_text().splitlines()
    start = next((i for i, x in enumerate(lines)
                  if x.lstrip("#").strip().startswith(section) and x.startswith("#")), None)
    if start is None:
        raise SystemExit(f"quote {spec!r}: docs/{page} has no heading {section!r}")
    tables = _tables(lines[start + 1:])
    index = int(nth or 1) - 1
    if index >= len(tables):
        raise SystemExit(f"quote {spec!r}: docs/{page}#{section} has {len(tables)} table(s)")
    table = tables[index]
    if rows.strip():
        keep = [r.strip() for r in rows.strip().removeprefix("rows:").split(",")]
        body = [x for x in table[2:] if x.split("|")[1].strip().strip("*") in keep]
        if not body:
            raise SystemExit(f"quote {spec!r}: no row of {keep}")
        table = table[:2] + body
    return "\n".join(table) + "\n"


def quoted_paragraphs(spec: str) -> str:
    """The paragraphs ``PAGE#SECTION`` names that open with a bold name (see the module);
    ``PAGE#SECTION | rows: A, B`` keeps those whose bold name is A or B."""
    spec, _, rows = spec.partition("|")
    page, _, section = spec.strip().partition("#")
    path = ROOT / "docs" / page
    if not path.is_file():
        raise SystemExit(f"quote-text {spec!r}: no docs/{page}")
    lines = path.read_text().splitlines()
    start = next((i for i, x in enumerate(lines)
                  if x.startswith("#") and x.lstrip("#").strip().startswith(section)), None)
    if start is None:
        raise SystemExit(f"quote-text {spec!r}: docs/{page} has no heading {section!r}")
    end = next((i for i in range(start + 1, len(lines)) if lines[i].startswith("#")),
               len(lines))  # fmt: skip
    body = "\n".join(lines[start + 1 : end])
    kept = [p.strip() for p in body.split("\n\n") if p.strip().startswith("**")]
    if rows.strip():
        keep = {r.strip() for r in rows.strip().removeprefix("rows:").split(",")}
        kept = [p for p in kept if p[2:].partition("**")[0] in keep]
    if not kept:
        raise SystemExit(f"quote-text {spec!r}: no paragraph opens with a bold name"
                         + (f" of {sorted(keep)}" if rows.strip() else ""))
    return "\n\n".join(kept) + "\n"


def _quotes(text: str) -> str:
    pattern = re.compile(r"(<!-- quote ([^>]*?) -->\n).*?(<!-- /quote -->)", re.S)
    text = pattern.sub(
        lambda m: m.group(1) + "\n" + quoted_table(m.group(2)) + "\n" + m.group(3), text
    )
    pattern = re.compile(r"(<!-- quote-text ([^>]*?) -->\n).*?(<!-- /quote-text -->)", re.S)
    return pattern.sub(
        lambda m: m.group(1) + "\n" + quoted_paragraphs(m.group(2)) + "\n" + m.group(3),
        text,
    )


PAGES = ("README.md", "docs/concepts/pipeline.md", "docs/analysis/benchmark.md",
         "docs/analysis/experiments.md", "docs/speed.md", "docs/concepts/learning.md",
         "docs/predictive.md")  # fmt: skip
"""The pages with generated blocks."""


def generated(path: Path) -> str:
    from copi.methods import methods_markdown

    text = path.read_text()
    if "<!-- methods" in text:
        text = _block(text, "methods", methods_markdown())
    if "<!-- results" in text:
        text = _block(text, "results", results_block())
    return _quotes(text)


def main() -> None:
    for rel in PAGES:
        path = ROOT / rel
        path.write_text(generated(path))
        print(f"wrote {rel}")


if __name__ == "__main__":
    main()

"""Write the generated blocks of the README and the docs (never typed by hand):

    python tools/update_docs.py

- between ``<!-- methods ... -->`` and ``<!-- /methods -->``: the registry's table of
  methods (:func:`copi.experiments.methods.methods_markdown`);
- between ``<!-- results ... -->`` and ``<!-- /results -->`` (README only): the headline
  rows, each quoted whole from the generated results page it names (``RESULTS`` below).

``tests/test_docs.py`` fails when a block differs from what this script would write.
"""

from __future__ import annotations

import re
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "src"))

RESULTS: list[tuple[str, str, str]] = [
    ("ceilings.md", "| crowd |",
     "**What is possible.** Every episode of every family is solvable by a clairvoyant; in "
     "crowds no method comes near it, and copi's learnt part does not yet beat the "
     "hand-written guard"),
    ("ceilings.md", "| indoor |", "Indoors, at level map, copi-learnt is the best method"),
    ("benchmark-bounds.md#star", "| compass-guard | map |",
     "**Where copi loses.** compass-guard — copi's hand-written guard with nothing learnt — "
     "has more successes than copi-learnt (the reference of Δ) in the paper's own star "
     "worlds at level map"),
    ("benchmark-bounds.md#maps", "| compass-guard | map |", "and in the maps family"),
    ("rl.md", "| indoor | map |",
     "**Against deep RL.** PPO trained in the family it is tested on (2M steps), beside "
     "copi-learnt (learnt once, without any task); this PPO learnt little beyond following "
     "the global direction (its last column: against `straight`)"),
    ("rl.md", "| ppo-chauffeur",
     "**A new task**, the homicidal chauffeur's evader: copi-learnt's capabilities "
     "unchanged, against PPO trained for the game with the same step budget"),
]
"""(source page, the row's first cell, what the line says of it): each headline is the
row of a generated table whose first cells match, quoted whole."""


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
    for page, first, label in RESULTS:
        file = page.partition("#")[0]
        out.append(f"{label} ([docs/{file}](docs/{file})):\n\n{quoted_row(page, first)}\n")
    return "\n".join(out)


def generated(path: Path) -> str:
    from copi.experiments.methods import methods_markdown

    text = path.read_text()
    text = _block(text, "methods", methods_markdown())
    if "<!-- results" in text:
        text = _block(text, "results", results_block())
    return text


def main() -> None:
    for rel in ("README.md", "docs/concepts/pipeline.md"):
        path = ROOT / rel
        path.write_text(generated(path))
        print(f"wrote {rel}")


if __name__ == "__main__":
    main()

"""The docs page of a ``copi reproduce`` run (never typed by hand):

    copi reproduce -o results/              # about 6 min on 2 cores
    python tools/reproduce_page.py results/ [--minutes M]

writes ``docs/reproduce.md`` (the run's ``report.md``: Experiments 1, 2 and 3) and its
figures as ``docs/reproduce-*.png``; ``docs/analysis/experiments.md`` quotes its tables
(``python tools/update_docs.py``).
"""

from __future__ import annotations

import argparse
import re
import shutil
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("run", type=Path, help="the directory copi reproduce wrote")
    ap.add_argument("--minutes", type=float, default=None, help="its wall time, to state")
    a = ap.parse_args()
    report = a.run / "report.md"
    if not report.is_file():
        raise SystemExit(f"{report}: no such file (run copi reproduce -o {a.run} first)")
    docs = ROOT / "docs"
    text = report.read_text()

    def figure(m: re.Match[str]) -> str:
        name = m.group(2)
        target = f"reproduce-{name}"
        shutil.copyfile(a.run / name, docs / target)
        return f"![{m.group(1)}]({target})"

    text = re.sub(r"!\[([^\]]*)\]\(([^)/]+\.png)\)", figure, text)
    took = f", {a.minutes:.0f} min on 2 cores" if a.minutes else ""
    head = (
        "# The paper's experiments, as `copi reproduce` reports them\n\n"
        f"<!-- generated: `copi reproduce -o results/` (seed 0{took}), then "
        "`python tools/reproduce_page.py results/` -->\n\n"
        "The report `copi reproduce` writes, unchanged but for its headings' level and its "
        "figures' names; [the experiments, read](analysis/experiments.md) explains it.\n\n"
    )
    # the report's experiments become this page's sections
    text = re.sub(r"^# ", "## ", text, flags=re.M)
    text = re.sub(r"\(`experiment1\.sqlite`, ", "(", text)
    (docs / "reproduce.md").write_text(head + text)
    print("wrote docs/reproduce.md")


if __name__ == "__main__":
    main()

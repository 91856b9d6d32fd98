"""A report copi wrote, kept as a docs page (never typed by hand):

    copi reproduce -o results/              # about 6 min on 2 cores
    python tools/report_page.py results/report.md docs/reproduce.md \\
        --title "The paper's experiments, as copi reproduce reports them" \\
        --command "copi reproduce -o results/ (seed 0, 6 min on 2 cores)"

writes the page (the report unchanged but for its headings, one level down under the
title, and its figures, copied beside the page as ``PAGE-*.png``) with a comment naming
the command that made it. The analysis pages quote its tables
(``python tools/update_docs.py``).
"""

from __future__ import annotations

import argparse
import re
import shutil
from pathlib import Path


def write_page(report: Path, page: Path, title: str, command: str, about: str = "") -> Path:
    """``report`` (Markdown with figures beside it) as ``page`` (see the module)."""
    text = report.read_text()

    def figure(m: re.Match[str]) -> str:
        target = f"{page.stem}-{m.group(2)}"
        shutil.copyfile(report.parent / m.group(2), page.parent / target)
        return f"![{m.group(1)}]({target})"

    text = re.sub(r"!\[([^\]]*)\]\(([^)/]+\.png)\)", figure, text)
    text = re.sub(r"^# ", "## ", text, flags=re.M)
    text = re.sub(r"\(`[^`]+\.sqlite`, ", "(", text)  # the store's path on this machine
    head = f"# {title}\n\n<!-- generated: `{command}`, then `python tools/report_page.py` -->\n\n"
    page.write_text(head + (f"{about}\n\n" if about else "") + text)
    return page


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("report", type=Path, help="the report copi wrote (report.md, run.md)")
    ap.add_argument("page", type=Path, help="the docs page to write")
    ap.add_argument("--title", required=True)
    ap.add_argument("--command", required=True, help="the command that made the report")
    ap.add_argument("--about", default="", help="a paragraph under the title")
    a = ap.parse_args()
    if not a.report.is_file():
        raise SystemExit(f"{a.report}: no such file (run the command first)")
    print(f"wrote {write_page(a.report, a.page, a.title, a.command, a.about)}")


if __name__ == "__main__":
    main()

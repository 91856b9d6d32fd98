"""A benchmark store's report as a docs page (never typed by hand):

    copi benchmark -o results/bench-mapping --episodes 200 --methods ...
    python tools/benchmark_page.py results/bench-mapping docs/benchmark-mapping.md \\
        --what "the sensor level with a map built on the fly" --command "copi benchmark ..."

writes the page (copi benchmark's report of ``STORE/benchmark.sqlite``, its title saying
what the run is, a comment the command that made it) and its figure beside it as
``PAGE.png``. The analysis pages quote its tables (``python tools/update_docs.py``).
"""

from __future__ import annotations

import argparse
import shutil
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
FIGURE = "benchmark_success_excess.png"


def write_page(store: Path, page: Path, what: str, command: str,
               against: str | None = None) -> Path:
    """``store``'s benchmark report as ``page`` (see the module), each row paired with
    ``against`` (copi benchmark's default when None)."""
    sys.path.insert(0, str(ROOT / "src"))
    from copi.reports import write_benchmark_report

    with tempfile.TemporaryDirectory() as tmp:
        text = write_benchmark_report(store / "benchmark.sqlite", tmp,
                                      against=against).read_text()
        shutil.copyfile(Path(tmp) / FIGURE, page.with_suffix(".png"))
    title, _, body = text.partition("\n")
    text = f"{title} ({what})\n\n<!-- generated: {command} -->\n" + body
    page.write_text(text.replace(f"]({FIGURE})", f"]({page.with_suffix('.png').name})"))
    return page


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("store", type=Path, help="the directory copi benchmark wrote")
    ap.add_argument("page", type=Path, help="the docs page to write")
    ap.add_argument("--what", required=True, help="what the run is (the title's end)")
    ap.add_argument("--command", required=True, help="the command(s) that made the store")
    ap.add_argument("--against", help="the method each row is paired with (as copi benchmark)")
    a = ap.parse_args()
    if not (a.store / "benchmark.sqlite").is_file():
        raise SystemExit(f"{a.store}: no benchmark.sqlite (run copi benchmark -o {a.store})")
    print(f"wrote {write_page(a.store, a.page, a.what, a.command, a.against)}")


if __name__ == "__main__":
    main()

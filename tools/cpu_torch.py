"""Exit 0 when pip can install a CPU build of torch 2.13.0 here without downloading a
CUDA one (the RL extra's torch), 1 otherwise, saying why. Used by ``make install``.

A CPU build is one whose version carries ``+cpu``, or any build on a platform whose
wheels are CPU-only (macOS, aarch64 Linux). Elsewhere ``pip install torch`` takes a
CUDA build of several GB: get a CPU one with ``pip install torch --index-url
https://download.pytorch.org/whl/cpu`` before ``pip install 'copi[rl]'``.
"""

from __future__ import annotations

import json
import platform
import subprocess
import sys
import tempfile
from pathlib import Path

WANT = "torch==2.13.0"


def main() -> int:
    try:
        import torch

        print(f"cpu_torch: torch {torch.__version__} is installed already")
        return 0
    except ImportError:
        pass
    with tempfile.TemporaryDirectory() as tmp:
        report = Path(tmp) / "report.json"
        done = subprocess.run(
            [sys.executable, "-m", "pip", "install", "--dry-run", "--no-deps", "--quiet",
             "--report", str(report), WANT],
            capture_output=True, text=True, timeout=300,
        )  # fmt: skip
        if done.returncode != 0 or not report.is_file():
            print(f"cpu_torch: pip cannot find {WANT} here", file=sys.stderr)
            return 1
        items = json.loads(report.read_text()).get("install", [])
    if not items:
        return 1
    version = items[0]["metadata"]["version"]
    cpu_only = platform.system() == "Darwin" or platform.machine() in ("aarch64", "arm64")
    if "+cpu" in version or cpu_only:
        print(f"cpu_torch: pip takes torch {version} (a CPU build)")
        return 0
    print(f"cpu_torch: pip would take torch {version}, not a CPU build", file=sys.stderr)
    return 1


if __name__ == "__main__":
    sys.exit(main())

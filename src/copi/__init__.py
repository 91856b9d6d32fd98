"""copi: Context-based Online Policy Instantiation.

The first and reference implementation of Rosman, "Context-based Online Policy
Instantiation for Multiple Tasks and Changing Environments". Importing copi registers its
Gymnasium environments (``copi/Navigation-v0``, ``copi/NavigationStatic-v0``).
"""

from __future__ import annotations

from importlib.metadata import PackageNotFoundError, version

import copi._kernel_cache  # noqa: F401  (first: the kernels' on-disk cache, see there)
from copi.envs.registration import register_envs

try:
    __version__ = version("copi")
except PackageNotFoundError:  # pragma: no cover - running from a source tree
    __version__ = "0+unknown"

register_envs()

__all__ = ["__version__"]

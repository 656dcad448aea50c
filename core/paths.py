"""Where EASE keeps files of its own outside the user's outputs.

Nothing here points into a source checkout: an installed wheel or the Blender
extension must not write next to ``site-packages``. Data that ships with the
package (body model, design templates) is read through
:mod:`importlib.resources` by the modules that own it.
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

APP = "ease"


def user_cache_dir() -> Path:
    """The per-user cache folder of EASE (not created).

    Returns
    -------
    Path
        ``%LOCALAPPDATA%\\ease\\cache`` on Windows; ``$XDG_CACHE_HOME/ease``
        elsewhere, ``~/.cache/ease`` when ``XDG_CACHE_HOME`` is unset or empty
        (macOS included, as many command-line tools do there).
    """
    if sys.platform == "win32":
        base = os.environ.get("LOCALAPPDATA") or str(Path.home() / "AppData" / "Local")
        return Path(base) / APP / "cache"
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / APP


def default_warp_cache() -> Path:
    """Point Warp's kernel cache at the user cache unless ``WARP_CACHE_PATH`` is set.

    Call before the first ``import warp``: Warp reads the variable once at
    initialisation. Only the first run compiles the kernels; later runs,
    from any working directory, load them from here.

    Returns
    -------
    Path
        The kernel cache folder in effect (the caller's ``WARP_CACHE_PATH``
        when set).
    """
    os.environ.setdefault("WARP_CACHE_PATH", str(user_cache_dir() / "warp"))
    return Path(os.environ["WARP_CACHE_PATH"])

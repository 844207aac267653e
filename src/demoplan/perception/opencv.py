"""OpenCV, imported without changing the environment.

cv2's loader puts its library folder before ``LD_LIBRARY_PATH`` and, where
the variable was unset, leaves an empty entry: the current folder, from which
every program demoplan starts afterwards (ffmpeg, a browser) would load
shared libraries. The variable is put back as it was once cv2 is loaded
(its own libraries are loaded by then). Import ``cv2`` from here.
"""

from __future__ import annotations

import os

_BEFORE = os.environ.get("LD_LIBRARY_PATH")

import cv2  # noqa: E402

if _BEFORE is None:
    os.environ.pop("LD_LIBRARY_PATH", None)
else:
    os.environ["LD_LIBRARY_PATH"] = _BEFORE

__all__ = ["cv2"]

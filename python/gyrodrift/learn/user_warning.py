"""Warnings that point at the user's line: the first caller outside gyrodrift and scikit-learn.

A warning raised deep inside a fit (a tuned value on its search bound, an ill-conditioned system, an interval
outlier) travels through scikit-learn's pipeline and gyrodrift's own layers; a fixed ``stacklevel`` would name one
of their lines (``sklearn/pipeline.py:645``). `warn_user` walks up the stack to the first frame whose file is in
neither package and names that line.
"""

from __future__ import annotations

import os
import sys
import warnings
from types import FrameType

__all__ = ["warn_user"]

_PACKAGE_DIR = os.path.dirname(os.path.dirname(os.path.abspath(__file__))) + os.sep


def warn_user(message: str, category: type[Warning]) -> None:
    """Warn ``message`` (``category``) at the first caller outside gyrodrift and scikit-learn.

    Parameters
    ----------
    message : str
        The warning's text, meant for the user as it is.
    category : type of Warning
        Its class (e.g. `gyrodrift.learn.tuning.SearchBoundWarning`).

    Notes
    -----
    When every frame is internal (a gyrodrift command), the warning names this function's caller.
    """
    sklearn = sys.modules.get("sklearn")  # not imported: none of its frames can be on the stack
    internal = (_PACKAGE_DIR,) if sklearn is None else (_PACKAGE_DIR, os.path.dirname(sklearn.__file__ or "") + os.sep)
    frame: FrameType | None = sys._getframe(1)
    level = 2  # 1 is this function, 2 its caller
    while frame is not None and frame.f_code.co_filename.startswith(internal):
        frame = frame.f_back
        level += 1
    warnings.warn(message, category, stacklevel=level if frame is not None else 2)

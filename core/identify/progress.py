"""Where a fit is, in words, for a page or a terminal that waits on it: ``progress(fraction,
message)`` told as the fit moves ("start 2 of 8, evaluation 40"), its fraction never going back.
"""

from __future__ import annotations

from collections.abc import Callable

# ``progress(fraction, message)``: where a fit is, in words ("start 2 of 8, evaluation 40")
Progress = Callable[[float, str], None]
PROGRESS_EVERY = 20  # evaluations of the model between two progress reports within a stage


def reporting(residuals, progress: Progress | None, fraction: float, stage: str,
               budget: int = 0, span: float = 0.0):
    """``residuals`` that say ``progress(fraction, "STAGE, evaluation N")`` every
    :data:`PROGRESS_EVERY` evaluations (``stage`` alone first), the fraction moving across
    ``span`` as the evaluations near ``budget``; ``residuals`` itself without ``progress``."""
    if progress is None:
        return residuals
    progress(fraction, stage)
    spent = [0]

    def counted(theta):
        spent[0] += 1
        if spent[0] % PROGRESS_EVERY == 0:
            progress(fraction + span * min(spent[0] / max(budget, 1), 1.0), f"{stage}, evaluation {spent[0]}")
        return residuals(theta)

    return counted


def forward(progress: Progress | None) -> Progress | None:
    """``progress`` told fractions that never go back (a refit after the profile restarts no
    bar)."""
    if progress is None:
        return None
    most = [0.0]

    def told(fraction: float, message: str):
        most[0] = max(most[0], min(fraction, 1.0))
        progress(most[0], message)

    return told

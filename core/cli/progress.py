"""Progress of one remap on stderr: stage, renders so far and current error."""

from __future__ import annotations

import math
import sys
import time


class RenderProgress:
    """Stage, renders so far and current error, on stderr; throttled when not a terminal."""

    def __init__(self, enabled: bool, header: str = ""):
        """``header`` is printed before the first line: a run that fails before rendering shows
        only its error."""
        self.enabled, self.header = enabled, header
        self.tty = sys.stderr.isatty()
        self.stage: str | None = None
        self.last = 0.0
        self.t0 = time.perf_counter()

    def __call__(self, stage: str, renders: int, error: float) -> None:
        if not self.enabled:
            return
        if self.header:
            print(self.header, file=sys.stderr, flush=True)
            self.header = ""
        now = time.perf_counter()
        err = "" if math.isnan(error) else f"  error {error:7.3%}"
        line = f"  [{now - self.t0:6.1f}s] {stage:<14} renders {renders:4d}{err}"
        if self.tty:
            end = "\n" if stage != self.stage and self.stage is not None else ""
            sys.stderr.write(("\n" if end else "\r") + line)
            if stage == "final":
                sys.stderr.write("\n")
            sys.stderr.flush()
        elif stage != self.stage or now - self.last > 2.0 or stage == "final":
            print(line, file=sys.stderr, flush=True)
            self.last = now
        self.stage = stage

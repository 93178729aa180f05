"""Shared by the benchmarks: a description of the machine and a median timer."""

from __future__ import annotations

import os
import platform
import statistics
import time


def machine() -> dict:
    """Where the figures came from."""
    cpu = platform.processor() or platform.machine()
    try:
        with open("/proc/cpuinfo") as fh:
            for line in fh:
                if line.startswith("model name"):
                    cpu = line.split(":", 1)[1].strip()
                    break
    except OSError:
        pass
    import numpy as np

    return {
        "cpu": cpu,
        "cores": os.cpu_count(),
        "python": platform.python_version(),
        "numpy": np.__version__,
        "platform": platform.platform(),
        "date": time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime()),
    }


def median_time(fn, repeat: int = 5, number: int = 1, clock=time.perf_counter) -> float:
    """Median over ``repeat`` runs of the seconds one call of ``fn`` takes.

    ``clock=time.process_time`` counts the CPU time of this process only: on a
    machine shared with other jobs, wall time also counts waiting for a core."""
    times = []
    for _ in range(repeat):
        t0 = clock()
        for _ in range(number):
            fn()
        times.append((clock() - t0) / number)
    return statistics.median(times)

"""Run every benchmark: ``.venv/bin/python -m benchmarks [name ...]`` (or ``make bench``).

Each ``benchmarks/bench_<name>.py`` has a ``main()`` that prints its figures and
ratios, measured side by side in one run. Names select a subset, e.g.
``python -m benchmarks ingest selection``.
"""
import importlib
import platform
import sys
import time
from pathlib import Path

import os


def machine() -> str:
    cpu = "unknown CPU"
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    mem = os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES") / 2**30
    return f"{cpu}, {os.cpu_count()} cores, {mem:.0f} GiB, Python {platform.python_version()}"


def main(argv: list[str]) -> int:
    here = Path(__file__).parent
    names = argv or sorted(p.stem[len("bench_"):] for p in here.glob("bench_*.py"))
    print(f"# floorscan benchmarks on {machine()}")
    for name in names:
        mod = importlib.import_module(f"benchmarks.bench_{name}")
        print(f"\n## {name}")
        t0 = time.perf_counter()
        mod.main()
        print(f"(benchmark {name} took {time.perf_counter() - t0:.1f} s)")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))

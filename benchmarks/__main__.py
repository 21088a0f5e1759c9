"""Run every benchmark: ``.venv/bin/python -m benchmarks [name [options] ...]`` (or ``make bench``).

Each ``benchmarks/bench_<name>.py`` has a ``main()`` that prints its figures and
ratios, measured side by side in one run. Names select a subset, e.g.
``python -m benchmarks ingest selection``; the words after a name, up to the next
name, are that benchmark's options, e.g.
``python -m benchmarks pipeline --datasets hallways --cores 2``.
"""
import importlib
import inspect
import os
import platform
import sys
import time
from pathlib import Path


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


def split_args(argv: list[str], known: list[str]) -> list[tuple[str, list[str]]]:
    """``["pipeline", "--datasets", "hallways", "walls"]`` -> ``[("pipeline", ["--datasets",
    "hallways"]), ("walls", [])]``; no name: every benchmark without options."""
    runs: list[tuple[str, list[str]]] = []
    for word in argv:
        if word in known:
            runs.append((word, []))
        elif runs:
            runs[-1][1].append(word)
        else:
            raise SystemExit(f"unknown benchmark {word!r}; known: {' '.join(known)}")
    return runs or [(name, []) for name in known]


def main(argv: list[str]) -> int:
    here = Path(__file__).parent
    known = sorted(p.stem[len("bench_"):] for p in here.glob("bench_*.py"))
    if argv[:1] in (["-h"], ["--help"]):
        print(f"{__doc__.strip()}\n\nbenchmarks: {' '.join(known)}; `python -m benchmarks <name> --help`: a benchmark's "
              "options; the measurements: benchmarks/README.md")
        return 0
    runs = split_args(argv, known)
    print(f"# floorscan benchmarks on {machine()}")
    for name, opts in runs:
        mod = importlib.import_module(f"benchmarks.bench_{name}")
        print(f"\n## {name}" + (f" {' '.join(opts)}" if opts else ""))
        t0 = time.perf_counter()
        if inspect.signature(mod.main).parameters:
            mod.main(opts)
        elif opts:
            raise SystemExit(f"benchmark {name} takes no options, got {opts}")
        else:
            mod.main()
        print(f"(benchmark {name} took {time.perf_counter() - t0:.1f} s)")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))

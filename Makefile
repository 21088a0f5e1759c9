# floorscan: `make run` runs the workflow on the default target (the demo) through the
# floorscan command, `make test` runs the tests, `make test-fast` the unit tests alone. Each creates .venv from the pinned, hashed
# environment.lock when it is missing or stale.
SHELL := /bin/bash
PYTHON ?= $(shell command -v python3.11 || command -v python3)
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.floorscan-installed
CORES ?= 2

.PHONY: run test test-fast report bench lock sysdeps clean-results help

# The demo with its evaluation, through the floorscan command: a line per finished job,
# then the answer (Snakemake's own output goes to .snakemake/floorscan/run.log).
run: $(STAMP)
	@$(BIN)/floorscan run --evaluate --cores $(CORES)

# The report (results/report.html) of the last `make run` or `floorscan run`.
report: $(STAMP)
	@$(BIN)/floorscan report

test: $(STAMP)
	$(BIN)/python -m pytest

# The unit tests alone, about a minute on 2 cores, for working: no Snakemake run, no
# recording of ../shared, nothing measured slow (markers set in tests/conftest.py).
# `make test` runs these and the rest.
test-fast: $(STAMP)
	$(BIN)/python -m pytest -m "not workflow and not realdata and not slow"

bench: $(STAMP)
	$(BIN)/python -m benchmarks

# Open3D's wheel links libusb-1.0 (Debian package libusb-1.0-0).
sysdeps:
	@if ldconfig -p | grep -q 'libusb-1.0.so.0'; then :; \
	elif [ "$$(id -u)" = 0 ] && command -v apt-get >/dev/null; then \
		echo "Installing libusb-1.0-0 (needed by Open3D)"; \
		apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq libusb-1.0-0 >/dev/null; \
	else \
		echo "Open3D needs the shared library libusb-1.0. Install it first, e.g. 'sudo apt-get install libusb-1.0-0'" >&2; exit 1; \
	fi

# The set-up, once (again when environment.lock or pyproject.toml changes): its time and
# disk were measured on a fresh clone with 2 cores (issue 47).
$(STAMP): environment.lock pyproject.toml | sysdeps
	@[ -n "$(PYTHON)" ] || { echo "Python 3.11 is needed (python3.11 or python3 on PATH)" >&2; exit 1; }
	@echo "Setting up $(VENV): installing the $(shell grep -c '==' environment.lock) pinned packages of environment.lock (about 3.5 minutes, 2.4 GB; once)"
	@[ -x $(BIN)/python ] || $(PYTHON) -m venv $(VENV)
	@$(BIN)/python -m pip install -q --disable-pip-version-check --require-hashes -r environment.lock
	@$(BIN)/python -m pip install -q --disable-pip-version-check --no-deps --no-build-isolation -e .
	@touch $(STAMP)

# Recompile the lock after editing requirements.in (needs uv: pip install uv).
lock:
	uv pip compile --python-version 3.11 --python-platform x86_64-manylinux_2_31 --generate-hashes requirements.in -o environment.lock

clean-results:
	rm -rf results

help:
	@echo "make run          set up .venv (once), then the demo with its evaluation: results/demo/front.html"
	@echo "make test         set up .venv (once), then every test (about 15 minutes on 2 cores)"
	@echo "make test-fast    the unit tests alone (about a minute)"
	@echo "make report       the HTML report of the last run: results/report.html"
	@echo "make bench        every benchmark (python -m benchmarks --help)"
	@echo "make lock         recompile environment.lock from requirements.in (needs uv)"
	@echo "make clean-results  remove results/"
	@echo "Your own recording or map: .venv/bin/floorscan run PATH (.venv/bin/floorscan run --help)"

# uasnav: `make demo` runs the main job, `make test` runs every check. Both start from nothing:
# they create .venv, install the Python dependencies and build the Rust extension with maturin.
SHELL := /bin/bash
PYTHON ?= python3
VENV ?= .venv
BIN := $(VENV)/bin
EXTRAS ?= test
RUST_SRC := $(shell find crates -name '*.rs' -o -name Cargo.toml) Cargo.toml Cargo.lock
PY_SRC := pyproject.toml

.PHONY: demo test setup browser rust-checks py-checks bench bench-python clean

demo: setup
	$(BIN)/uasnav report --out build/report

test: setup rust-checks py-checks

setup: $(VENV)/.built browser

# The browser tests of `uasnav serve` drive Debian's chromium through Playwright's executable_path
# (Playwright's own browser download does not work on these machines); installed when missing.
browser:
	@command -v chromium >/dev/null || (apt-get update -q && DEBIAN_FRONTEND=noninteractive apt-get install -y -q chromium)

$(BIN)/python:
	$(PYTHON) -m venv $(VENV)
	$(BIN)/pip install --upgrade pip maturin

$(VENV)/.built: $(BIN)/python $(RUST_SRC) $(PY_SRC)
	$(BIN)/maturin develop --release --extras $(EXTRAS) -q
	$(BIN)/python -c 'import uasnav._core'
	touch $@

rust-checks:
	cargo fmt --all --check
	cargo clippy --workspace --all-targets -- -D warnings
	cargo test --workspace --exclude py-uasnav --release
	cargo build -p nav-core --no-default-features
	cargo bench --workspace --no-run

py-checks: setup
	$(BIN)/ruff check python tests benches scripts
	$(BIN)/ruff format --check python tests benches scripts
	$(BIN)/python -m mypy.stubtest uasnav._core
	$(BIN)/python -m pytest -q

bench: setup
	cargo bench -p uasnav-benches

bench-python: setup
	$(BIN)/python benches/bench_python.py

clean:
	rm -rf $(VENV) build target

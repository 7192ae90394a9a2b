# uasnav: `make demo` runs the main job, `make test` runs every check. Both start from nothing:
# they create .venv, install the Python dependencies and build the Rust extension with maturin.
# `make demo` installs what the report needs (the base install + the utm and fleet extras);
# `make test` adds the test and docs tools and Chromium for the browser tests, and runs
# independent steps side by side (see `test`).
SHELL := /bin/bash
PYTHON ?= python3
VENV ?= .venv
BIN := $(VENV)/bin
EXTRAS ?= web,utm,fleet,test,docs
DEMO_EXTRAS := utm,fleet
RUST_SRC := $(shell find crates -name '*.rs' -o -name Cargo.toml) Cargo.toml Cargo.lock
PY_SRC := pyproject.toml
DIST := build/dist
# maturin finds zig (the ziglang wheel) through the venv's python on PATH
ZIG_ENV := PATH="$(CURDIR)/$(BIN):$$PATH"
MATURIN_BUILD := $(ZIG_ENV) $(BIN)/maturin build --release --strip --zig --compatibility manylinux2014 -q

.PHONY: demo test test-lane setup browser rust-checks py-checks lane-tests bench bench-python clean wheel dist docs publish-check

demo: $(VENV)/.built-demo
	$(BIN)/uasnav report --out build/report

TEST_JOBS ?= 2
# Two phases, TEST_JOBS steps at a time: the development install beside the Rust checks, then
# the Python tests beside the other steps (one after the other: the wheel, the lane's Python
# tests, the embedded build, the docs, the crate's publish check). Each step's output is printed
# whole when the step ends (--output-sync), so logs stay readable.
test:
	+$(MAKE) -j$(TEST_JOBS) --output-sync=target setup rust-checks
	+$(MAKE) -j$(TEST_JOBS) --output-sync=target py-checks test-lane

test-lane:
	+$(MAKE) -j1 --no-print-directory wheel lane-tests embedded docs publish-check

setup: $(VENV)/.built browser

# Debian packages are installed one apt run at a time (make -j may reach two at once).
APT_INSTALL := flock /tmp/uasnav-apt.lock sh -c 'apt-get update -q && DEBIAN_FRONTEND=noninteractive apt-get install -y -q "$$@"' apt

# The browser tests of `uasnav serve` drive Debian's chromium through Playwright's executable_path
# (Playwright's own browser download does not work on these machines); installed when missing.
browser:
	@command -v chromium >/dev/null || $(APT_INSTALL) chromium

# The virtual environment is created in the same step as the development install.
NEW_VENV := test -x $(BIN)/python || { $(PYTHON) -m venv $(VENV) && $(BIN)/pip install --upgrade pip maturin; }

$(VENV)/.built: $(RUST_SRC) $(PY_SRC)
	$(NEW_VENV)
	$(BIN)/maturin develop --release --extras $(EXTRAS) -q
	$(BIN)/python -c 'import uasnav._core'
	touch $@

$(VENV)/.built-demo: $(RUST_SRC) $(PY_SRC)
	$(NEW_VENV)
	$(BIN)/maturin develop --release --extras $(DEMO_EXTRAS) -q
	$(BIN)/python -c 'import uasnav._core'
	touch $@

# The x86_64 wheel (abi3, manylinux2014 through zig), built once and installed by the package
# tests (tests/test_package.py) in fresh virtual environments.
wheel: $(DIST)/.x86_64

$(DIST)/.x86_64: $(VENV)/.built $(RUST_SRC) $(PY_SRC) $(shell find python -name '*.py' -o -name '*.pyi')
	rm -f $(DIST)/uasnav-*x86_64*.whl
	$(MATURIN_BUILD) --target x86_64-unknown-linux-gnu --out $(DIST)
	touch $@

# Everything to publish: the x86_64 and aarch64 wheels and the sdist, each checked.
dist: wheel
	rustup target add aarch64-unknown-linux-gnu
	rm -f $(DIST)/uasnav-*aarch64*.whl $(DIST)/uasnav-*.tar.gz
	$(MATURIN_BUILD) --target aarch64-unknown-linux-gnu --out $(DIST)
	$(BIN)/maturin sdist --out $(DIST)
	for w in $(DIST)/uasnav-*.whl; do $(BIN)/auditwheel show $$w | tr '\n' ' ' | grep -q 'manylinux_2_17' || { echo "error: $$w is not manylinux2014"; exit 1; }; done
	ls -l $(DIST)

# The documentation site (mkdocs-material, offline: no web fonts, no CDN), warnings as errors
# (not -q: mkdocs drops its warnings below the log level before --strict can count them).
docs: setup
	$(BIN)/python docs/gen_reference.py
	NO_MKDOCS_2_WARNING=1 $(BIN)/mkdocs build --strict -d build/site
	$(BIN)/python docs/check_offline.py build/site

# The core crate as crates.io would receive it, and its docs without warnings.
publish-check:
	RUSTDOCFLAGS="-D warnings" cargo doc -p uasnav-core --no-deps -q
	cargo publish --dry-run -p uasnav-core --allow-dirty -q
	cargo run -q --release -p uasnav-core --example zupt_loop
	cargo run -q --release -p uasnav-core --example allan_no_alloc

# --all-targets: the tests, the examples and the criterion benches (each run once, as a test).
rust-checks:
	cargo fmt --all --check
	cargo clippy --workspace --all-targets -- -D warnings
	cargo test --workspace --exclude py-uasnav --release --all-targets
	cargo build -p uasnav-core --no-default-features

# Test modules that run in the second lane of `make test` (lane-tests), beside the other Python
# tests: the wheel installed in fresh environments, the code of the docs, the Dask cluster.
# `make py-checks lane-tests` runs every Python test.
LANE_TESTS := tests/test_package.py tests/test_docs.py tests/test_fleet.py

py-checks: setup
	$(BIN)/ruff check python tests benches scripts docs/*.py
	$(BIN)/ruff format --check python tests benches scripts docs/*.py
	$(BIN)/python -m mypy.stubtest uasnav._core
	$(BIN)/python -m pytest -q --durations=15 $(addprefix --ignore=,$(LANE_TESTS))

lane-tests: setup wheel
	$(BIN)/python -m pytest -q -p no:cacheprovider --basetemp=build/pytest-lane --durations=5 $(LANE_TESTS)

# nav-core on Cortex-M4F and Cortex-M7 in QEMU (bit-identical to the host, f32 within derived
# bounds of f64), the C interface (header regenerated by the pinned cbindgen and compared, a C
# program built with gcc) and the rate-budget table (BENCHMARKS.md). Installs what it needs.
.PHONY: embedded
EMB := target/embedded
FW := crates/nav-firmware
FW_ELF := thumbv7em-none-eabihf/release/nav-firmware
CBINDGEN_VERSION := 0.29.4
CBINDGEN := $(CURDIR)/$(EMB)/tools/bin/cbindgen
LLVM_BIN = $(shell rustc --print sysroot)/lib/rustlib/$(shell rustc -vV | sed -n 's/^host: //p')/bin

embedded:
	@command -v qemu-system-arm >/dev/null || $(APT_INSTALL) qemu-system-arm
	@command -v gcc >/dev/null || $(APT_INSTALL) gcc
	rustup target add thumbv7em-none-eabihf
	rustup component add llvm-tools
	@$(CBINDGEN) --version 2>/dev/null | grep -qx "cbindgen $(CBINDGEN_VERSION)" || cargo install --locked --debug --quiet cbindgen@$(CBINDGEN_VERSION) --root $(EMB)/tools
	cd $(FW) && cargo build --release --quiet --target-dir ../../$(EMB)/host
	cd $(FW) && RUSTFLAGS="-C target-cpu=cortex-m4" cargo build --release --quiet --target thumbv7em-none-eabihf --target-dir ../../$(EMB)/m4
	cd $(FW) && RUSTFLAGS="-C target-cpu=cortex-m7" cargo build --release --quiet --target thumbv7em-none-eabihf --target-dir ../../$(EMB)/m7
	cargo build -p nav-ffi --release --quiet
	cd crates/nav-ffi && $(CBINDGEN) --quiet --config cbindgen.toml --output ../../$(EMB)/nav_ffi.h
	diff -u crates/nav-ffi/include/nav_ffi.h $(EMB)/nav_ffi.h
	python3 $(FW)/check.py c-inputs $(EMB)/inputs.h
	gcc -std=c11 -Wall -Wextra -Werror -O2 -Icrates/nav-ffi/include -I$(EMB) crates/nav-ffi/tests/c/ffi_test.c \
		target/release/libnav_ffi.a -lgcc_s -lutil -lrt -lpthread -lm -ldl -lc -o $(EMB)/ffi_test
	$(EMB)/ffi_test > $(EMB)/ffi_test.txt
	python3 $(FW)/check.py $(EMB)/host/release/nav-firmware $(EMB)/m4/$(FW_ELF) $(EMB)/m7/$(FW_ELF) \
		--size $(LLVM_BIN)/llvm-size --nm $(LLVM_BIN)/llvm-nm --objdump $(LLVM_BIN)/llvm-objdump \
		--c-output $(EMB)/ffi_test.txt

bench: setup
	cargo bench -p uasnav-benches

bench-python: setup
	$(BIN)/python benches/bench_python.py

clean:
	rm -rf $(VENV) build target

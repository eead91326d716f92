# One entry point for everything a developer (and CI) runs.
#   make test   build the extension, lint everything, run the Rust and Python tests
#   make test-fast  the Python tests not marked slow (the edit-test loop, under a minute)
#   make bench  criterion benches (cargo bench) and pytest-benchmark comparisons
#   make wheel  one abi3 wheel (CPython 3.10+) in target/wheels
#   make wheel-check  install that wheel into a fresh venv away from the source and run it
#   make fmt    format Rust and Python in place
#   make docs   the gallery's examples, then the documentation site into site/ (warnings are
#               errors; the docs extra)
#   make figures  regenerate the documentation's figures from the package
PYTHON ?= python
# The suite on both cores of the 2-core machine, one file per worker (a file's tests share
# their session's map cache); PYTEST_ARGS= runs it in one process.
PYTEST_ARGS ?= -n 2 --dist loadfile --no-loadscope-reorder

.PHONY: test test-fast build llvm lint test-rust test-python bench fmt validate wheel wheel-check docs figures

test: build lint test-rust test-python

# Editable install of the extension into the current Python (release build via maturin).
build:
	$(PYTHON) -m pip install --no-build-isolation --no-deps -e . -q

lint:
	cargo fmt --all -- --check
	cargo clippy --workspace --all-targets -- -D warnings
	ruff check .
	ruff format --check .
	$(PYTHON) -m mypy.stubtest rainuav._core

test-rust:
	cargo test --workspace

# pycraf (ITU-R P.452, a reference the terrain tests check against) goes in without its
# declared dependencies: they pull in pytest plugins that break pytest's command line; what it
# needs at run time (astropy, pyproj, scipy, rasterio) is in the test extra.
test-python: build llvm
	$(PYTHON) -m pip install -q --no-deps 'pycraf>=2.1,<3'
	$(PYTHON) -m pytest $(PYTEST_ARGS)

test-fast: build
	$(PYTHON) -m pytest $(PYTEST_ARGS) -m "not slow"

# Sionna RT (the test extra's reference ray tracer) runs on the CPU through LLVM 19: Debian's
# libllvm19, installed here where it is missing (found by rainuav.radio.tracer).
llvm:
	@ldconfig -p | grep -q 'libLLVM.so.19\|libLLVM-19.so' || apt-get install -y -q libllvm19 \
		|| (apt-get update -q && apt-get install -y -q libllvm19) \
		|| (echo "install Debian's libllvm19 (the tracer's CPU backend)" && false)

bench: build
	cargo bench -p rainuav-core
	MIEPYTHON_USE_JIT=1 $(PYTHON) -m pytest benches --benchmark-enable --benchmark-only --benchmark-columns=min,median,mean,stddev,rounds

wheel:
	rm -f target/wheels/rainuav-*.whl
	maturin build --release --out target/wheels

wheel-check: wheel
	PYTHON=$(PYTHON) bash .ci/wheel-check target/wheels

fmt:
	cargo fmt --all
	ruff check --fix .
	ruff format .

validate: build
	$(PYTHON) -m rainuav.validate rain --out validation

docs:
	$(PYTHON) docs/gallery.py
	NO_MKDOCS_2_WARNING=1 $(PYTHON) -m mkdocs build --strict --site-dir site

figures: build
	$(PYTHON) docs/figures.py

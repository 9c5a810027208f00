# The README's two commands are `make demo` and `make test`; both set everything up themselves.
SHELL := /bin/bash
VENV := .venv
PY := $(VENV)/bin/python
export VIRTUAL_ENV := $(CURDIR)/$(VENV)
export PATH := $(CURDIR)/$(VENV)/bin:$(PATH)
RUST_SOURCES := $(shell find crates -name '*.rs' -o -name Cargo.toml -o -name '*.json') Cargo.toml pyproject.toml

.PHONY: demo test test-fast build lint fmt bench quick-start rust-test ffi-test c-cpp-examples c-example cpp-example cpp-containers examples docs pytest wheel clean mutants results-table

demo: build
	$(PY) -m tvist.cli demo

# Every example runs once: the C and C++ ones in ffi-test, the Python ones in pytest
# (tests/integration/test_examples.py, which also checks what they print).
test: build rust-test ffi-test lint docs pytest

# The edit-compile-test loop: ruff, tvist-core's tests and the unit tier (tests/unit: fast,
# no long simulator runs, no sockets, so nothing realtime; see docs/test-quality.md).
# `make test` still runs everything.
test-fast: build lint
	cargo test -p tvist-core -q
	$(PY) -m pytest -q --durations=10 $(PYTEST_PARALLEL) tests/unit -m "not slow"

$(PY):
	python3 -m venv $(VENV)
	$(PY) -m pip install -q --upgrade pip "maturin>=1.8,<2"

# Release build of the extension plus the package's runtime, test and docs dependencies.
$(VENV)/.built: $(PY) $(RUST_SOURCES)
	maturin develop --release --extras test,docs -q
	touch $@

build: $(VENV)/.built

rust-test:
	cargo test --workspace --exclude tvist-py -q
	cargo fmt --all --check
	cargo clippy --workspace --all-targets -q -- -D warnings

# C API: release library; the C example linked statically and, with the README's line as
# printed, dynamically; the C++ example (header-only tvist.hpp) on a map file; tvist.hpp's
# container overloads. All are run.
FFI_LIBS := -lgcc_s -lutil -lrt -lpthread -lm -ldl
CXX ?= c++
ffi-test: build c-cpp-examples cpp-containers
	grep -m1 -e '-ltvist -lm -Wl,-rpath' README.md > target/c/readme_dynamic_link.sh
	bash -e target/c/readme_dynamic_link.sh
	./target/c/shape_move_shared
	./target/cpp/hpp_containers_17
	./target/cpp/hpp_containers_20

# The C and C++ examples, each linked statically, run (the C++ one on a map file).
c-cpp-examples: build c-example cpp-example
	./target/c/shape_move
	$(PY) -c "import tvist; tvist.DynamicMap.paper_ur5e().save('target/cpp/paper_ur5e.json')"
	./target/cpp/shape_with_map ur5e 5.0 0 0 0.05 target/cpp/paper_ur5e.json 0.002 zv

# The C example against libtvist.a.
c-example:
	cargo build -p tvist-ffi --release -q
	@mkdir -p target/c
	cc -std=c11 -Wall -Wextra -Werror -Iinclude examples/c/shape_move.c \
		target/release/libtvist.a $(FFI_LIBS) -o target/c/shape_move

# The C++ example against libtvist.a (the pytest parity test uses it too).
cpp-example:
	cargo build -p tvist-ffi --release -q
	@mkdir -p target/cpp
	$(CXX) -std=c++17 -Wall -Wextra -Werror -Iinclude examples/cpp/shape_with_map.cpp \
		target/release/libtvist.a $(FFI_LIBS) -o target/cpp/shape_with_map

# tvist.hpp's container overloads against the pointer forms, as C++17 and as C++20.
cpp-containers:
	cargo build -p tvist-ffi --release -q
	@mkdir -p target/cpp
	for std in 17 20; do \
		$(CXX) -std=c++$$std -Wall -Wextra -Werror -Iinclude tests/cpp/hpp_containers.cpp \
			target/release/libtvist.a $(FFI_LIBS) -o target/cpp/hpp_containers_$$std || exit 1; \
	done

# Every program in examples/: the C and C++ ones, then the Python ones, each Python one in a
# fresh working directory (they write their logs, maps and plots there). Each takes seconds.
EXAMPLES_DIR := target/examples
examples: build c-cpp-examples
	@rm -rf $(EXAMPLES_DIR) && mkdir -p $(EXAMPLES_DIR)
	@for script in examples/*.py; do \
		echo "== $$script"; \
		mkdir -p $(EXAMPLES_DIR)/$$(basename $$script .py); \
		(cd $(EXAMPLES_DIR)/$$(basename $$script .py) && \
			MPLBACKEND=Agg $(CURDIR)/$(PY) $(CURDIR)/$$script) || exit 1; \
	done

# The documentation site (mkdocs.yml) into target/site; any warning fails the build. The
# results pages are made from what `make demo` and `make bench` left in out/.
docs: build
	NO_MKDOCS_2_WARNING=1 DISABLE_MKDOCS_2_WARNING=true $(VENV)/bin/mkdocs build --strict -q

# Release wheel (abi3, Python >= 3.10) into dist/: installs without a Rust toolchain.
wheel: $(PY)
	$(VENV)/bin/maturin build --release --out dist

lint: $(PY)
	$(VENV)/bin/ruff check python tests benches examples tools docs/gen_pages.py
	$(VENV)/bin/ruff format --check python tests benches examples tools docs/gen_pages.py

# pytest in PYTEST_WORKERS processes (pytest-xdist; default: the cores, at most 2; 0: in this
# process), worksteal: a worker that runs out of tests takes the other's last ones. Then the
# realtime tests, in one process and apart from everything else (docs/test-quality.md: the
# twin server keeps real time at 500 Hz; beside a second worker's server and campaign, a
# ur_rtde client crashed its process inside its own code).
PYTEST_WORKERS ?= $(shell n=$$(nproc 2>/dev/null || echo 1); echo $$(( n < 2 ? n : 2 )))
PYTEST_PARALLEL := -n $(PYTEST_WORKERS) --dist worksteal

pytest: build
	$(PY) -m pytest -q --durations=15 $(PYTEST_PARALLEL) -m "not realtime"
	$(PY) -m pytest -q --durations=10 -p no:xdist -m realtime

fmt: $(PY)
	cargo fmt --all
	$(VENV)/bin/ruff format python tests benches examples tools docs/gen_pages.py
	$(VENV)/bin/ruff check --fix python tests benches examples tools docs/gen_pages.py

# Each benchmark's output is also kept in out/bench/ for the docs' benchmarks page.
# The README's quick start run as written (the twin server on UR's ports on 127.0.0.1, so
# nothing else may serve them); what it printed goes to out/quick-start/run.json, which the
# docs' quick-start page shows. Not part of `make test`.
quick-start: build
	$(PY) tools/quick_start.py

bench: build
	@mkdir -p out/bench
	set -o pipefail; cargo bench -q -p tvist-core --bench cycle | tee out/bench/cycle.txt
	set -o pipefail; cargo bench -q -p tvist-core --bench robot_pass | tee out/bench/robot_pass.txt
	set -o pipefail; cargo bench -q -p tvist-core --bench modal_step | tee out/bench/modal_step.txt
	set -o pipefail; $(PY) benches/bench_shape.py | tee out/bench/bench_shape.txt
	set -o pipefail; $(PY) benches/bench_sim.py | tee out/bench/bench_sim.txt

# README.md's results table: every row whose command has written its outputs (out/, see
# docs/results/index.md) is read into docs/results/headline.json, and the table is rendered
# from that record; rows without outputs keep their entry (tools/results_table.py).
results-table: build
	$(PY) tools/results_table.py --update

# Mutation testing (not part of `make test`; see docs/mutants.md for run times): cargo-mutants on
# tvist-core's numerical modules (.cargo/mutants.toml), then tools/python_mutants.py on the
# Python numerics. MUTANTS_SHARD=k/n runs one n-th of the Rust mutants; PY_MUTANTS sets the
# sample size per Python module. Reports: target/mutants/mutants.out, target/mutants-python.
TOOLS := $(CURDIR)/.tools
CARGO_MUTANTS := $(TOOLS)/bin/cargo-mutants
MUTANTS_SHARD ?= 0/20
PY_MUTANTS ?= 12

$(CARGO_MUTANTS):
	cargo install cargo-mutants --locked --root $(TOOLS)

mutants: build $(CARGO_MUTANTS)
	-nice -n 15 $(CARGO_MUTANTS) mutants --gitignore true --jobs 1 --shard $(MUTANTS_SHARD) --sharding round-robin --output target
	nice -n 15 $(PY) tools/python_mutants.py --per-module $(PY_MUTANTS)

clean:
	rm -rf $(VENV) target out dist

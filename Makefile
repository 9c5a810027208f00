# The README's two commands are `make demo` and `make test`; both set everything up themselves.
SHELL := /bin/bash
VENV := .venv
PY := $(VENV)/bin/python
export VIRTUAL_ENV := $(CURDIR)/$(VENV)
export PATH := $(CURDIR)/$(VENV)/bin:$(PATH)
RUST_SOURCES := $(shell find crates -name '*.rs' -o -name Cargo.toml) Cargo.toml pyproject.toml

.PHONY: demo test build lint fmt bench rust-test ffi-test pytest clean

demo: build
	$(PY) -m tvist.cli demo

test: build rust-test ffi-test lint pytest

$(PY):
	python3 -m venv $(VENV)
	$(PY) -m pip install -q --upgrade pip "maturin>=1.8,<2"

# Release build of the extension plus the package's runtime and test dependencies.
$(VENV)/.built: $(PY) $(RUST_SOURCES)
	maturin develop --release --extras test -q
	touch $@

build: $(VENV)/.built

rust-test:
	cargo test --workspace --exclude tvist-py -q
	cargo fmt --all --check
	cargo clippy --workspace --all-targets -q -- -D warnings

# C API: release library, the C example compiled against include/tvist.h and libtvist.a, run.
FFI_LIBS := -lgcc_s -lutil -lrt -lpthread -lm -ldl
ffi-test:
	cargo build -p tvist-ffi --release -q
	@mkdir -p target/c
	cc -std=c11 -Wall -Wextra -Werror -Iinclude examples/c/shape_move.c \
		target/release/libtvist.a $(FFI_LIBS) -o target/c/shape_move
	./target/c/shape_move

lint: $(PY)
	$(VENV)/bin/ruff check python tests benches examples
	$(VENV)/bin/ruff format --check python tests benches examples

pytest: build
	$(PY) -m pytest -q

fmt: $(PY)
	cargo fmt --all
	$(VENV)/bin/ruff format python tests benches examples
	$(VENV)/bin/ruff check --fix python tests benches examples

bench: build
	cargo bench -q -p tvist-core --bench cycle
	$(PY) benches/bench_shape.py
	$(PY) benches/bench_sim.py

clean:
	rm -rf $(VENV) target out

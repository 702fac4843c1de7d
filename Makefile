# spicethermal: `make demo` runs the main job, `make test` runs the tests.
PY      ?= python3
VENV    := .venv
BIN     := $(VENV)/bin
STAMP   := $(VENV)/.installed

.PHONY: setup demo test check lint bench firmware clean

setup: $(STAMP) ngspice

$(STAMP): pyproject.toml constraints.txt
	test -x $(BIN)/python || $(PY) -m venv $(VENV)
	$(BIN)/pip install -q --upgrade pip
	$(BIN)/pip install -q -c constraints.txt -e '.[dev]'
	touch $(STAMP)

ngspice:
	@if ! command -v ngspice >/dev/null 2>&1 || ! ldconfig -p | grep -q libngspice.so.0 || ! command -v chromium >/dev/null 2>&1; then \
	  echo "installing ngspice, libngspice0 and chromium (apt)"; \
	  SUDO=$$( [ "$$(id -u)" = 0 ] || echo sudo ); \
	  $$SUDO apt-get update -qq && DEBIAN_FRONTEND=noninteractive $$SUDO apt-get install -y -qq ngspice libngspice0 chromium; \
	fi

firmware:
	$(MAKE) -C firmware host

demo: setup firmware
	$(BIN)/spicethermal demo -o out/demo
	@echo "the spicethermal command is in $(VENV): in each new shell, run  . $(BIN)/activate"

# ruff, the firmware tests and every test, two processes (pytest-xdist): the README's and CI's command
test: setup firmware
	$(BIN)/ruff check -q spicethermal tests bench
	$(MAKE) -C firmware test
	$(BIN)/python -m pytest -q -n 2 --dist loadgroup

# the edit loop: everything but the tests marked slow (whole-pipeline runs)
check: setup firmware
	$(BIN)/python -m pytest -q -n 2 --dist loadgroup -m 'not slow and not benchmark'

lint: setup
	$(BIN)/ruff check spicethermal tests bench

bench: setup firmware   # accuracy and speed studies: minutes, not part of `make test`
	$(BIN)/python bench/table.py --all

clean:
	rm -rf out build dist

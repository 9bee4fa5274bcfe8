PY ?= python3
VENV := .venv
BIN := $(VENV)/bin
RUN_STAMP := $(VENV)/.installed-run
TEST_STAMP := $(VENV)/.installed-test

.PHONY: bench test install clean

$(BIN)/python:
	$(PY) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip

$(RUN_STAMP): $(BIN)/python pyproject.toml
	$(BIN)/python -m pip install --quiet -e .
	touch $@

$(TEST_STAMP): $(BIN)/python pyproject.toml
	$(BIN)/python -m pip install --quiet -e '.[test]'
	touch $@ $(RUN_STAMP)

install: $(RUN_STAMP)

bench: $(RUN_STAMP)
	$(BIN)/shootout run configs/quick.yaml
	@echo "report: results/quick/report.html"

# two test files at a time (most tests wait on processes they start), then the timing verdicts alone
test: $(TEST_STAMP)
	$(BIN)/python -m pytest -q -n 2 --dist loadfile -m 'not slow and not serial'
	$(BIN)/python -m pytest -q -m 'serial and not slow'

clean:
	rm -rf $(VENV) build *.egg-info

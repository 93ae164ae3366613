# The targets README tells a person to run.
VENV   := .venv
PY     := $(VENV)/bin/python
STAMP  := $(VENV)/.installed

.PHONY: run test test-fast lint corpus model bench

$(STAMP): pyproject.toml
	test -x $(PY) || python3 -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -e ".[dev]"
	touch $(STAMP)

run: $(STAMP)            ## set up and start the app on its shipped defaults
	$(VENV)/bin/mtrnn serve

test: $(STAMP)           ## set up and run the whole suite (fast, slow, browser, cluster)
	./scripts/ensure-chromium
	./scripts/ensure-axe
	$(VENV)/bin/pytest -q

test-fast: $(STAMP)      ## the quick subset while developing
	$(VENV)/bin/pytest -q -m "not slow and not browser and not cluster"

lint: $(STAMP)
	$(VENV)/bin/ruff check .

corpus: $(STAMP)         ## rebuild the shipped encoded corpus from seed 0
	$(VENV)/bin/mtrnn corpus build --seed 0

model: $(STAMP)          ## retrain the shipped models from their seed: default (end_to_end) and faithful
	$(VENV)/bin/mtrnn train --mode end_to_end --fold 0 --seed 0 --out data/artefacts/models/default
	$(VENV)/bin/mtrnn train --mode faithful --fold 0 --seed 0 --out data/artefacts/models/faithful

bench: $(STAMP)
	for b in benchmarks/*.py; do $(PY) $$b; done

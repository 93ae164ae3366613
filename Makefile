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

corpus: $(STAMP)         ## rebuild both shipped encoded corpora from seed 0: the paper's and the wide variety's
	$(VENV)/bin/mtrnn corpus build --seed 0
	$(VENV)/bin/mtrnn corpus build --seed 0 --variety wide --recordings 16 --out data/artefacts/corpus_wide.npz

model: $(STAMP)          ## retrain the shipped models from their seed: default (end_to_end, wide corpus) and faithful
	$(VENV)/bin/mtrnn train --mode end_to_end --fold 0 --seed 0 --corpus data/artefacts/corpus_wide.npz --out data/artefacts/models/default
	$(VENV)/bin/mtrnn train --mode faithful --fold 0 --seed 0 --set training.optimiser=rprop --out data/artefacts/models/faithful

bench: $(STAMP)
	for b in benchmarks/*.py; do $(PY) $$b; done

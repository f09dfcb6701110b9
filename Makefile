# Two commands do everything on a fresh machine: `make demo` and `make test`.
# Set-up (Debian's libvulkan1 for bpy, a Python 3.11 venv with pinned packages) runs only when
# something is missing or requirements-dev.txt changed, so repeated runs start at once.

PYTHON ?= python3.11
VENV   := .venv
PY     := $(VENV)/bin/python
STAMP  := $(VENV)/.requirements.sha256
REQ_SHA = $(shell cat requirements.txt requirements-dev.txt | sha256sum | cut -c1-64)
DEMO   ?= demo
JOBS   ?= 0

.PHONY: setup system-deps test test-compat demo dist bench clean

setup: system-deps
	@if [ ! -x $(PY) ]; then echo "creating $(VENV) with $(PYTHON)"; $(PYTHON) -m venv $(VENV); fi
	@if [ "$$(cat $(STAMP) 2>/dev/null)" != "$(REQ_SHA)" ]; then \
	  echo "installing pinned packages into $(VENV) (bpy is about 800 MB the first time)"; \
	  $(PY) -m pip install --quiet --disable-pip-version-check -r requirements-dev.txt && \
	  echo "$(REQ_SHA)" > $(STAMP); \
	fi

# Debian's libvulkan1 (bpy needs libvulkan.so.1) and chromium (the report's browser test)
system-deps:
	@missing=""; \
	ldconfig -p 2>/dev/null | grep -q 'libvulkan.so.1' || missing="$$missing libvulkan1"; \
	command -v chromium >/dev/null || missing="$$missing chromium"; \
	if [ -n "$$missing" ]; then \
	  echo "installing Debian's$$missing"; \
	  SUDO=$$( [ "$$(id -u)" = 0 ] || echo sudo ); \
	  $$SUDO apt-get update -qq && $$SUDO apt-get install -y -qq $$missing >/dev/null; \
	fi

test: setup
	$(PY) -m pytest -q

# The built linux zip installed into older Blenders (bpy 4.2 LTS and 4.5 LTS, each in its own venv
# under build/compat, made once): install, register, and one small headless analysis per renderer
# through the installed package (tests/compat_check.py). Separate from `make test`: the two venvs
# are about 2 GB to download the first time.
COMPAT_BPY       ?= 4.2.23 4.5.15
COMPAT_RENDERERS ?= freestyle lineart
COMPAT_DIR       := build/compat

test-compat: setup
	$(PY) tools/build_dist.py --platforms linux-x64 --out $(COMPAT_DIR)/dist
	@failed=""; for v in $(COMPAT_BPY); do \
	  venv=$(COMPAT_DIR)/bpy-$$v; \
	  if [ ! -x $$venv/bin/python ] || ! $$venv/bin/python -c "import bpy" 2>/dev/null; then \
	    echo "creating $$venv (bpy $$v)"; rm -rf $$venv; $(PYTHON) -m venv $$venv; \
	    $$venv/bin/python -m pip install --quiet --disable-pip-version-check bpy==$$v; \
	  fi; \
	  rm -rf $(COMPAT_DIR)/work-$$v; \
	  echo "== bpy $$v"; \
	  $$venv/bin/python tests/compat_check.py $(COMPAT_DIR)/dist/style_coanalysis-*-linux_x64.zip \
	    $(COMPAT_DIR)/work-$$v $(COMPAT_RENDERERS) || failed="$$failed $$v"; \
	done; \
	if [ -n "$$failed" ]; then echo "test-compat failed for bpy$$failed"; exit 1; fi

# The main job on the bundled sample collection: 120 generated shapes, 20% of them labelled.
demo: setup
	$(PY) -m style_coanalysis sample --out $(DEMO)/sample --size 120 --seed 0
	$(PY) tools/pick_labels.py $(DEMO)/sample/labels.csv --fraction 0.2 --seed 0 --out $(DEMO)/labels_20pct.csv
	$(PY) -m style_coanalysis analyze $(DEMO)/sample/sample.blend --out $(DEMO)/result \
	    --labels $(DEMO)/labels_20pct.csv --jobs $(JOBS) --cache $(DEMO)/cache
	@echo "results: $(DEMO)/result/report.html, report.json, result.blend"

# Four validated extension zips (linux-x64, windows-x64, macos-arm64, macos-x64) in dist/.
dist: setup
	$(PY) tools/build_dist.py --out dist

bench: setup
	@for b in bench/bench_*.py; do echo "== $$b"; $(PY) $$b || exit 1; done

clean:
	rm -rf build dist $(DEMO) .pytest_cache

# Two commands on a fresh machine: `make demo` and `make test`. Each creates .venv if missing.
PYTHON ?= python3
VENV   := .venv
PY     := $(VENV)/bin/python
STAMP  := $(VENV)/.installed

.PHONY: demo test bench clean services

# TrackEval (HOTA) without its declared dependencies: see the comment in pyproject.toml.
TRACKEVAL := trackeval==1.3.0

$(STAMP): pyproject.toml Makefile
	test -x $(PY) || $(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -e '.[test,baseline,redis,serve,browser]'
	$(PY) -m pip install --quiet --no-deps '$(TRACKEVAL)'
	@echo "compiling the trackers' kernels once (cached in src/**/__pycache__; a few minutes on a small machine)"
	$(PY) -m worldtrack.warmup
	touch $(STAMP)

demo: $(STAMP)
	$(VENV)/bin/worldtrack demo

test: $(STAMP) services
	$(PY) -m pytest

# The shared-map and live-stream tests start their own redis-server, ffmpeg and an RTSP server
# (GStreamer's, through the system Python's PyGObject: tests/map/rtsp_server.py) (Debian packages); the
# tests of worldtrack serve drive Debian's chromium through Playwright (no browser download).
services:
	@command -v redis-server >/dev/null && command -v ffmpeg >/dev/null || \
	  { apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq redis-server ffmpeg >/dev/null; } || \
	  echo "redis-server/ffmpeg could not be installed: the shared-map and live-stream tests will be skipped"
	@dpkg -s gir1.2-gst-rtsp-server-1.0 gstreamer1.0-plugins-good python3-gi >/dev/null 2>&1 || \
	  { apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq gir1.2-gst-rtsp-server-1.0 \
	    gstreamer1.0-plugins-good python3-gi >/dev/null; } || \
	  echo "GStreamer's RTSP server could not be installed: the RTSP camera test will be skipped"
	@command -v chromium >/dev/null || \
	  { apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq chromium >/dev/null; } || \
	  echo "chromium could not be installed: the browser tests of worldtrack serve will be skipped"

bench: $(STAMP)
	$(PY) benchmarks/run_all.py

clean:
	rm -rf $(VENV) demo_out .pytest_cache

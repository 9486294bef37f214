# synthgen developer entry points. `make demo` and `make test` work on a fresh Debian 12
# machine: they install missing system packages, create .venv, build and install.
SHELL := /bin/bash
VENV := .venv
PY := $(VENV)/bin/python
BUILD := build
JOBS ?= $(shell nproc)
APT_PACKAGES := cmake gcc g++ make pkg-config libembree-dev libopenimageio-dev python3-openimageio \
  libpugixml-dev libeigen3-dev libssl-dev pybind11-dev libassimp-dev libtbb-dev libgtest-dev libopenvdb-dev \
  python3-dev python3-venv python3-pip python3-setuptools python3-wheel python3-numpy \
  python3-yaml python3-pytest python3-tqdm python3-distributed python3-matplotlib assimp-testmodels blender-data \
  fonts-dejavu-core tesseract-ocr python3-torch python3-torchvision python3-pil python3-scipy
SUDO := $(shell [ "$$(id -u)" = 0 ] || echo sudo)

.PHONY: demo test build deps venv install clean cpp-test py-test

demo: install
	$(VENV)/bin/synthgen demo -o out/demo
	$(VENV)/bin/synthgen run scenarios/default.yaml -o out/dataset -n 4 --resume --no-progress
	$(VENV)/bin/synthgen verify out/dataset
	$(VENV)/bin/synthgen run scenarios/augmented_road.yaml -o out/augmented -n 4 --resume --no-progress
	$(VENV)/bin/synthgen verify out/augmented

test: install
	cd $(BUILD) && ctest --output-on-failure -j $(JOBS)
	$(PY) -m pytest -q tests/python

# System packages: only the missing ones are installed.
.stamp-deps: Makefile
	@missing=$$(for p in $(APT_PACKAGES); do dpkg-query -W -f='$${Status}\n' $$p 2>/dev/null | grep -q "install ok installed" || echo $$p; done); \
	if [ -n "$$missing" ]; then \
	  echo "installing system packages:" $$missing; \
	  $(SUDO) apt-get update -qq && DEBIAN_FRONTEND=noninteractive $(SUDO) apt-get install -y -qq $$missing; \
	fi
	@touch $@
deps: .stamp-deps

$(PY): .stamp-deps
	/usr/bin/python3 -m venv --system-site-packages $(VENV)
	@touch $@
venv: $(PY)

$(BUILD)/CMakeCache.txt: CMakeLists.txt .stamp-deps | $(PY)
	cmake -S . -B $(BUILD) -DCMAKE_BUILD_TYPE=Release -DPython3_EXECUTABLE=$(abspath $(PY)) \
	  -DSYNTHGEN_PYTHON_OUTPUT_DIR=$(abspath python/synthgen) -DSYNTHGEN_BUILD_TESTS=ON

build: $(BUILD)/CMakeCache.txt
	cmake --build $(BUILD) -j $(JOBS)

# Editable install: the package in python/ is what .venv imports; the native module is
# built in place by CMake (incremental).
.stamp-install: pyproject.toml setup.py | $(PY) $(BUILD)/CMakeCache.txt
	$(PY) -m pip install --no-build-isolation --no-deps --no-index -q -e .
	@touch $@
install: build .stamp-install

clean:
	rm -rf $(BUILD) .stamp-install python/synthgen/_core*.so python/synthgen/libsynthgen_oiio.so python/synthgen/libsynthgen_vdb.so python/synthgen/synthgen-reader

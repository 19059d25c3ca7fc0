# Two commands do all the set-up on a fresh Debian machine:
#   make demo   - the main job: an example Mitsuba scene of ten materials, two of them textured,
#                 converted to Blender Cycles (out/library: library.blend, index.html); the textured
#                 ones texel by texel through the remap tables shipped in configs/tables/built/
#   make test   - the test suite
# Both create .venv and install what they need; `system-deps` adds libLLVM 19 so Mitsuba
# can use its fast llvm_ad_rgb variant (without it the tool falls back to scalar_rgb),
# Debian's Chromium (the tests open the HTML report in it; the threejs adapter renders in it),
# Xvfb and Mesa's OpenGL (the materialx adapter renders with MaterialX's own GLSL on a virtual display),
# and Node.js with npm, which installs three.js and the Khronos glTF validator, pinned by
# adapters/threejs/web/package-lock.json, into adapters/threejs/web/node_modules.

PYTHON ?= python3.11
VENV   ?= .venv
PY     := $(VENV)/bin/python
STAMP  := $(VENV)/.installed-stamp
LLVM19 := /usr/lib/x86_64-linux-gnu/libLLVM.so.19.1

.PHONY: demo test test-all extension system-deps clean

$(STAMP): pyproject.toml
	@command -v $(PYTHON) >/dev/null || { echo "needs $(PYTHON) (the bpy wheels are built for Python 3.11)"; exit 1; }
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -e '.[all]'
	@touch $(STAMP)

MESA   := /usr/lib/x86_64-linux-gnu
APT_NEEDS := $(if $(wildcard $(LLVM19)),,libllvm19) $(if $(wildcard /usr/bin/chromium),,chromium) \
             $(if $(wildcard /usr/bin/node),,nodejs) $(if $(wildcard /usr/bin/npm),,npm) \
             $(if $(wildcard /usr/bin/Xvfb),,xvfb) $(if $(wildcard $(MESA)/dri/swrast_dri.so),,libgl1-mesa-dri) \
             $(if $(wildcard $(MESA)/libGLX_mesa.so.0),,libglx-mesa0)
WEB    := adapters/threejs/web
THREE  := $(WEB)/node_modules/.package-lock.json

system-deps:
	@if [ "$$(uname -s)" = Linux ] && [ -n "$(strip $(APT_NEEDS))" ] && command -v apt-get >/dev/null; then \
	  if [ "$$(id -u)" = 0 ]; then SUDO=; else SUDO=sudo; fi; \
	  echo "installing $(strip $(APT_NEEDS)) (Mitsuba's llvm variant; the browser the report is tested in and three.js renders in; Node.js and npm for three.js; a virtual display and Mesa's OpenGL for MaterialX's renderer)"; \
	  $$SUDO apt-get update -qq && $$SUDO apt-get install -y -qq $(APT_NEEDS) >/dev/null; \
	fi

$(THREE): $(WEB)/package-lock.json | system-deps
	cd $(WEB) && npm ci --no-audit --no-fund --loglevel=error
	@touch $(THREE)

TABLES := configs/tables/built

demo: system-deps $(STAMP) $(THREE)
	$(VENV)/bin/remap convert examples/library/scene.xml --to cycles --out out/library \
	  --table $(TABLES)/mitsuba-roughconductor-to-cycles-principled.json \
	  --table $(TABLES)/mitsuba-roughconductor-to-cycles-metallic.json \
	  --table $(TABLES)/mitsuba-roughplastic-to-cycles-principled.json

test: system-deps $(STAMP) $(THREE)
	$(PY) -m pytest

test-all: system-deps $(STAMP) $(THREE)
	$(PY) -m pytest --run-slow

extension: $(STAMP)   # the Blender extension's installable zip, built and validated by Blender's own tool
	$(PY) extension/build.py --out dist

clean:
	rm -rf out dist .pytest_cache

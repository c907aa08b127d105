#!/usr/bin/env bash
# Installs the anchor of the closure benchmarks: Mitsuba 3.9.1 from PyPI into the virtual
# environment VENV (created if missing), plus Debian's libllvm19, which Dr.Jit's LLVM backend
# (the `llvm_ad_rgb` variant) loads at run time. Idempotent; `cargo bench -p uplift --bench
# engines -- --mitsuba BSDF` runs it before bsdf_rate.py.
set -euo pipefail
venv="${1:?usage: setup.sh VENV}"
apt_install() {
    export DEBIAN_FRONTEND=noninteractive
    apt-get install -y -qq "$@" >/dev/null 2>&1 || { apt-get update -qq && apt-get install -y -qq "$@"; }
}
dpkg -s libllvm19 >/dev/null 2>&1 || apt_install libllvm19
if [ ! -x "$venv/bin/python" ]; then
    python3 -m venv "$venv" 2>/dev/null || { apt_install python3-venv && python3 -m venv "$venv"; }
fi
if ! "$venv/bin/python" -c "import mitsuba, sys; sys.exit(mitsuba.__version__ != '3.9.1')" >/dev/null 2>&1; then
    "$venv/bin/python" -m pip install -q mitsuba==3.9.1
fi
"$venv/bin/python" -c "import mitsuba as mi; mi.set_variant('llvm_ad_rgb'); print('mitsuba', mi.__version__, 'llvm_ad_rgb ready')"

#!/usr/bin/env bash
# Installs the anchor of the neural benchmark: PyTorch (CPU) from PyPI into the virtual
# environment VENV (created if missing). Idempotent; `cargo bench -p uplift --bench neural --
# --torch` runs it before mlp_rate.py. PyPI's Linux wheel brings CUDA libraries it does not use
# on a CPU (a few GiB of download the first time).
set -euo pipefail
venv="${1:?usage: setup.sh VENV}"
if [ ! -x "$venv/bin/python" ]; then
    python3 -m venv "$venv" 2>/dev/null || {
        export DEBIAN_FRONTEND=noninteractive
        apt-get install -y -qq python3-venv >/dev/null 2>&1 || { apt-get update -qq && apt-get install -y -qq python3-venv; }
        python3 -m venv "$venv"
    }
fi
if ! "$venv/bin/python" -c "import torch" >/dev/null 2>&1; then
    "$venv/bin/python" -m pip install -q torch
fi
"$venv/bin/python" -c "import torch; print('torch', torch.__version__, 'ready')"

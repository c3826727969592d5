# Sourced by the device-call scripts: the checkout's root as the working folder, the carried
# wheels (.whl/: trimesh, colour-science, xatlas) installed into /tmp/site, unbuffered output,
# no GPU preallocation, and quiet() to drop XLA's log lines.
set -u
OUT=${OUT:?OUT must name an output folder}
mkdir -p "$OUT"
cd "$(dirname "${BASH_SOURCE[0]}")/.."
python3 -m pip install -q --no-index --no-deps --no-compile --no-cache-dir --upgrade \
  --target /tmp/site .whl/*.whl || exit 1
export PYTHONUNBUFFERED=1 XLA_PYTHON_CLIENT_PREALLOCATE=false
quiet() { grep -v "^WARNING\|^I0000\|^E0000\|^W0000"; }

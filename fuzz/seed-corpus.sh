#!/usr/bin/env bash
# Fills fuzz/corpus/<target>/ with the seed documents: the snapshot inputs (tests/in), the
# malformed documents (tests/malformed) and, when UPLIFT_MTLX_DATA is set, MaterialX's TestSuite
# — the same seeds compiler/tests/integration/fuzz_stable.rs starts from. libFuzzer adds what it finds.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
root=$(dirname "$here")
for target in read check compile; do
  mkdir -p "$here/corpus/$target"
  dirs=("$root/tests/in" "$root/tests/malformed")
  if [ -n "${UPLIFT_MTLX_DATA:-}" ]; then dirs+=("$UPLIFT_MTLX_DATA/Materials/TestSuite"); fi
  find "${dirs[@]}" -name '*.mtlx' -print0 | while IFS= read -r -d '' f; do
    cp "$f" "$here/corpus/$target/$(sha1sum "$f" | cut -c1-16).mtlx"
  done
done
echo "seeded $(ls "$here/corpus/read" | wc -l) documents per target"

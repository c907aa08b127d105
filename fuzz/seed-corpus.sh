#!/usr/bin/env bash
# Fills fuzz/corpus/<target>/ with the seed documents: the snapshot inputs (tests/in), the
# malformed documents (tests/malformed) and, when UPLIFT_MTLX_DATA is set, MaterialX's TestSuite
# — the same seeds compiler/tests/integration/fuzz_stable.rs starts from — and fuzz/corpus/gltf,
# fuzz/corpus/rule with the enhance targets' seeds. libFuzzer adds what it finds.
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
# The enhance targets: glTF assets built by uplift_enhance::fuzz_entry::gltf_seeds (and
# MaterialX's Geometry/*.glb) and the shipped and example rules, written by the stable runner.
UPLIFT_FUZZ_WRITE_SEEDS="$here/corpus" cargo test --manifest-path "$root/Cargo.toml" -p uplift --test integration fuzz_enhance:: -q >/dev/null
echo "seeded $(ls "$here/corpus/read" | wc -l) documents per compiler target, $(ls "$here/corpus/gltf" | wc -l) glTF assets, $(ls "$here/corpus/rule" | wc -l) rules"

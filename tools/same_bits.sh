#!/usr/bin/env bash
# The SHA-256 of every bundled scene's EXRs (frames 1 to 3) rendered by both methods at 48x36, 4 passes, on two
# threads: run before and after a change that must not change a bit, and compare.
#
#     bash tools/same_bits.sh target/release/caustic > before.txt
set -euo pipefail
binary=${1:-target/release/caustic}
here=$(cd "$(dirname "$0")/.." && pwd)
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
for scene in "$here"/scenes/*.gltf; do
    for method in sppm vcm; do
        name=$(basename "$scene" .gltf)
        dir="$out/$name-$method"
        if "$binary" render "$scene" --method "$method" --resolution 48x36 --passes 4 --threads 2 \
            --frames 1-3 --progress none --out "$dir" > "$dir.log" 2>&1; then
            for exr in "$dir"/*.exr; do
                echo "$name $method $(basename "$exr") $(sha256sum "$exr" | cut -c1-16)"
            done
        else
            echo "$name $method refused: $(tail -n 1 "$dir.log")"
        fi
    done
done

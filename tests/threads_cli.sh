#!/usr/bin/env bash
# --threads 1 opens no thread: every command that takes --threads is run with it on work large enough that the
# automatic rule would start a team, under build/tests/libthread_count.so (tests/thread_count.c: a preloaded
# pthread_create that counts every thread the process starts, OpenMP's, OpenImageIO's and OpenEXR's pools
# included). The same run with --threads 2 must start some: the control that shows the work is parallel at all
# and the counter sees it. (The brief: many copies run at once, so a run never opens threads it cannot use.)
# Needs python3 for the report's glTF-free inputs. Ends with "N passed, N failed".
set -u
build=$(cd "${MR_BUILD:-build}" && pwd)
bin="$build/bin/matremap"
root="${MR_ROOT:-$(cd "$(dirname "$0")/.." && pwd)}"
shared="${MR_SHARED:-$root/../shared}"
counter="$build/tests/libthread_count.so"
floppy="$shared/assets/specgloss/FloppyDisk-sketchfab/scene.gltf"
duck="$shared/assets/specgloss/Duck-pbrSpecularGlossiness/glTF-pbrSpecularGlossiness/Duck.gltf"
duck_dir=$(dirname "$duck")
bottle="$shared/assets/metalrough/WaterBottle/glTF"
sphere_obj="$shared/assets/paper/matsphere.obj"
source "$(dirname "$0")/lib/cli_harness.sh"
# The automatic rule must be free to start a team: no inherited limit.
unset OMP_NUM_THREADS OMP_THREAD_LIMIT MATREMAP_WEIGHTS
# AddressSanitizer wants its runtime first in the library list; the counter, preloaded, comes before it.
export ASAN_OPTIONS="${ASAN_OPTIONS:+$ASAN_OPTIONS:}verify_asan_link_order=0"

[ -f "$counter" ] || { echo "FAIL  $counter is missing (make check builds it)"; echo "0 passed, 1 failed"; exit 1; }

# started -- command...: runs the command under the counter and prints the threads it and its children started
# (-1 when the command failed, its error shown). Threads that libraries' initialisers start as they are loaded
# are not among them (thread_count.c says why); their sum goes to $tmp/at_load.
started() {
    shift
    rm -f "$tmp/count"
    if ! MR_THREAD_COUNT_FILE="$tmp/count" LD_PRELOAD="$counter" "$@" >out 2>err; then
        sed 's/^/      /' err | head -5 >&2
        echo -1
        return
    fi
    awk '$1 == "at_load" { n += $2 } END { print n + 0 }' "$tmp/count" >"$tmp/at_load" 2>/dev/null
    awk '$1 == "threads" { n += $2; seen = 1 } END { print seen ? n : -1 }' "$tmp/count" 2>/dev/null || echo -1
}

# none NAME -- command...: the command, whose --threads is given as the word THREADS, starts no thread with
# --threads 1 and some with --threads 2. The two runs are made in folders of their own ($tmp/one, $tmp/two), so
# that outputs, given relative, do not meet (a sweep would resume the first's file); later commands read the
# first's.
mkdir -p "$tmp/one" "$tmp/two"
with_threads() { # N command...: the command with THREADS replaced by --threads N
    local n=$1 a
    shift
    local args=()
    for a in "$@"; do if [ "$a" = THREADS ]; then args+=(--threads "$n"); else args+=("$a"); fi; done
    started -- "${args[@]}"
}
none() {
    local name=$1 one two
    shift 2
    one=$(cd "$tmp/one" && with_threads 1 "$@")
    local loaded
    loaded=$(cat "$tmp/at_load" 2>/dev/null)
    two=$(cd "$tmp/two" && with_threads 2 "$@")
    check "$name: --threads 1 starts no thread ($one; ${loaded:-0} by libraries as they were loaded)" \
        test "$one" = 0
    check "$name: --threads 2 starts some ($two)" test "$two" -gt 0
}

# One convention: every command takes --threads 0 (automatic) and says so the same way in its --help.
for command in render ssim remap metal2spec spec2metal gltf sweep learn convert dataset train report; do
    expect "$command --threads 0 is accepted" 0 "" -- "$bin" "$command" --threads 0 --help
    check "$command --help: '--threads ... (default 0: automatic'" \
        sh -c "'$bin' $command --help | grep -q -- '--threads .*(default 0: automatic'"
done

none "render, a sphere at 256^2" -- "$bin" render ggx diffuse=0.2 f0=0.04 alpha=0.3 --size 256 THREADS -o sphere.exr
none "render, the paper's material sphere mesh ($(grep -c '^f ' "$sphere_obj") faces)" -- \
    "$bin" render ggx diffuse=0.2 f0=0.04 alpha=0.3 --mesh "$sphere_obj" --size 96 THREADS -o mesh.exr
none "ssim, 256^2" -- "$bin" ssim "$tmp/one/sphere.exr" "$tmp/two/sphere.exr" THREADS
expect "ssim --threads out of range: a usage error naming it" 1 "--threads '-1': expected an integer in \\[0, 1024\\]" \
    -- "$bin" ssim "$tmp/one/sphere.exr" "$tmp/two/sphere.exr" --threads -1
none "remap" -- "$bin" remap --from ggx alpha=0.2 f0=0.3 --to ward THREADS
none "metal2spec, WaterBottle's 2048^2 maps" -- "$bin" metal2spec --basecolor "$bottle/WaterBottle_baseColor.png" \
    --metallic-roughness "$bottle/WaterBottle_occlusionRoughnessMetallic.png" THREADS -o bottle_
none "spec2metal --method mlp, the Duck's 512^2 map" -- "$bin" spec2metal --diffuse "$duck_dir/DuckCM.png" \
    --specular 0.1 --glossiness 0.5 --method mlp THREADS -o duck_
none "gltf spec2metal, FloppyDisk" -- "$bin" gltf spec2metal "$floppy" THREADS -o floppy.gltf
none "sweep" -- "$bin" sweep --from ward diffuse=0 --to ggx diffuse=0 --grid alpha=0.03:0.4:6:log \
    specular=0.03:0.25:2 --size 32 THREADS -o sweep.csv
none "learn --method svr" -- "$bin" learn "$tmp/one/sweep.csv" --method svr THREADS -o wg.mrt
none "convert, a 2048^2 map" -- "$bin" convert --from ward --to ggx specular=0.1 \
    alpha="$bottle/WaterBottle_occlusionRoughnessMetallic.png":g --transform "$tmp/one/wg.mrt" THREADS -o conv_
none "dataset, 24 pairs on the Duck" -- "$bin" dataset --samples 24 --seed 3 --asset "$duck" THREADS -o pairs.csv
none "train" -- "$bin" train "$tmp/one/pairs.csv" --hidden 8 --epochs 5 THREADS -o net.mlp
none "report" -- "$bin" report THREADS -o report ggx alpha=0.3 -- ggx alpha=0.5
finish

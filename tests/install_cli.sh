#!/usr/bin/env bash
# install_cli.sh — the installed tree is usable by another program: `make install` into a scratch DESTDIR, then
# programs compiled with nothing but `pkg-config --cflags --libs matremap` (no --static): every installed public
# header alone, matremap.h alone, and the "Typical use" lines at the top of matremap.h, which must compile and run
# (so that the example cannot go stale again).
#
# The install reuses this build's objects: make is given the same BUILD, and under `make check` / `make asan` the
# parent make's command-line variables (CFLAGS, SAN) reach it through MAKEFLAGS, so nothing is rebuilt.
root="${MR_ROOT:-$(cd "$(dirname "$0")/.." && pwd)}"
build="${MR_BUILD:-$root/build}"
source "$(dirname "$0")/lib/cli_harness.sh"

dest="$tmp/dest"
expect "make install into a DESTDIR" 0 "" -- make -C "$root" -s BUILD="${build#"$root"/}" DESTDIR="$dest" install
prefix=$(find "$dest" -name matremap.pc -path '*/pkgconfig/*' | head -n 1)
check "matremap.pc is installed" test -n "$prefix"
export PKG_CONFIG_PATH="$(dirname "$prefix")" PKG_CONFIG_SYSROOT_DIR="$dest"
cflags=$(pkg-config --cflags matremap) && libs=$(pkg-config --libs matremap)
check "pkg-config knows matremap" test -n "$libs"
# A sanitizer build's library needs the sanitizer runtimes at link time; they are not a dependency of the library.
case "${MAKEFLAGS:-}" in *fsanitize=*) libs="$libs -fsanitize=address,undefined" ;; esac

include_dir=$(pkg-config --variable=includedir matremap) # with the sysroot (DESTDIR) already in front
headers=$(cd "$include_dir" && find . -name '*.h' | sed 's|^\./||' | sort)
check "the public headers are installed (sweep.h, report.h, mr_gltf.h among them)" \
    bash -c "echo '$headers' | grep -qx remap/sweep.h && echo '$headers' | grep -qx report/report.h && \
             echo '$headers' | grep -qx gltf/mr_gltf.h"
for h in $headers; do
    printf '#include "%s"\nint main(void) { return 0; }\n' "$h" >"$tmp/one.c"
    expect "installed $h compiles alone" 0 "" -- cc -std=c11 -Wall -Wextra -Werror -pedantic -c "$tmp/one.c" \
        -o "$tmp/one.o" $cflags
done
# Every installed header is reachable from matremap.h, the one include.
not_included=""
for h in $headers; do
    [ "$h" = matremap.h ] || grep -q "#include \"$h\"" "$include_dir/matremap.h" || not_included="$not_included $h"
done
check "matremap.h includes every other installed header (missing:${not_included:- none})" test -z "$not_included"

# The typical-use lines: from the line after "Typical use" up to the blank comment line, without their " *   ".
sed -n '/^ \* Typical use/,/^ \*$/p' "$include_dir/matremap.h" | sed '1d;$d' | sed 's/^ \*   //' >"$tmp/body.c"
check "matremap.h has its typical-use lines" test "$(wc -l <"$tmp/body.c")" -ge 10
{
    printf '#include <stdio.h>\n#include <matremap.h>\n\nint main(void) {\n'
    sed 's/^/    /' "$tmp/body.c"
    printf '}\n'
} >"$tmp/typical.c"
expect "the typical use compiles with pkg-config --cflags --libs matremap" 0 "" -- \
    cc -std=c11 -Wall -Wextra -Werror "$tmp/typical.c" -o "$tmp/typical" $cflags $libs
expect "the typical use runs: Ward remapped into GGX" 0 \
    "^(converged|at-bound|unreachable|local-minimum|under-resolved), SSIM 0\.9[0-9]+$" -- bash -c "cd '$tmp' && ./typical"
check "... ggx.exr is written" test -s "$tmp/ggx.exr"

# The example program of docs/examples: a glTF asset converted in one call, through the installed library.
expect "docs/examples/convert_asset.c compiles with pkg-config --cflags --libs matremap" 0 "" -- \
    cc -std=c11 -Wall -Wextra -Werror "$root/docs/examples/convert_asset.c" -o "$tmp/convert_asset" $cflags $libs
duck="$(cd "$root/.." && pwd)/shared/assets/specgloss/Duck-pbrSpecularGlossiness/glTF-pbrSpecularGlossiness/Duck.gltf"
mkdir -p "$tmp/duck"
expect "... and converts the Duck with weighted" 0 "^material 0 'blinn3-fx': converted, 512x512, [0-9]+ texels flagged$" \
    -- "$tmp/convert_asset" "$duck" "$tmp/duck/duck.gltf" weighted
check "... writing the asset and its new textures" test -s "$tmp/duck/duck.gltf" -a -s "$tmp/duck/duck_m0_basecolor.png"
expect "... and names a method it does not know" 1 "unknown \\(valid: weighted, mlp, mean, khronos, extension\\)" -- \
    "$tmp/convert_asset" "$duck" "$tmp/duck/x.gltf" nope

# The Python package (docs/python.md), installed beside the library it loads (not under a sanitizer: an
# AddressSanitizer library cannot load into an uninstrumented Python).
site=$(find "$dest" -type d -name matremap -path '*-packages/*' | head -n 1)
check "the Python package is installed" test -f "$site/__init__.py" -a -f "$site/_config.py"
case "${MAKEFLAGS:-}" in
*fsanitize=*) ;;
*) expect "... imports outside the tree and loads the installed libmatremap.so.0" 0 \
       "^$dest/.*/lib/libmatremap\.so\.0 0\.1\.0 \(8, 8, 3\)$" -- bash -c "cd '$tmp' && env -u MATREMAP_LIBRARY \
       PYTHONPATH='$(dirname "$site")' /usr/bin/python3 -c 'import matremap; print(matremap.library_path, \
       matremap.version(), matremap.render(\"ggx\", size=8).shape)'" ;;
esac
finish

#!/usr/bin/env bash
# ssim_crosscheck.sh — matremap's SSIM against an independent implementation, ssim.js (npm, pinned in
# tests/node/package-lock.json), on generated 8-bit greyscale PNGs with real content.
#
# Design (docs/metrics.md, "Cross-check"):
#   1. tests/node/ssim_crosscheck.js draws the images in JavaScript and encodes them with pngjs: a lit sphere
#      with noise, a noisier copy, a blurred copy, a shifted copy, a contrast-reduced copy, an unrelated image,
#      and two larger pairs for ssim.m's downsampling rule. oiiotool makes a JPEG-compressed copy (quality 30,
#      decoded back to PNG once, so both sides read the same pixels).
#   2. matremap's side is the project's command-line tool, `$MR_BUILD/bin/matremap ssim A B --json`, i.e.
#      mr_img_read (8-bit sRGB decode) + mr_ssim (display encode, BT.601 luma, SSIM); `--downsample` for the
#      pairs that compare ssim.m's downsampling.
#   3. ssim.js's side: {ssim: 'original'} (Wang's ssim.m, not its default 'weber' variant), with its
#      downsampling disabled for full-resolution pairs. Greyscale images make both sides compute on identical
#      grey levels: ssim.js rounds its luma to whole 8-bit levels (77R+150G+29B+128 >> 8), matremap keeps
#      BT.601 luma in floating point; for R = G = B both are exactly the stored level (see the .js header).
#   4. Each pair must agree within 1e-3 (in practice within a few 1e-9: our side holds the decoded images as
#      linear floats, so the sRGB round trip rounds a little).
# Pairs marked "note" are printed for information and not counted: for an even downsampling factor ssim.js
# pads before the image where MATLAB's imfilter (kernel origin floor((f+1)/2)) looks forward, so the two
# average shifted 2x2 blocks; matremap follows MATLAB.
#
# Requirements: node and npm (the tests/node/node_modules install runs `npm ci` only when it is missing),
# oiiotool, and a built matremap (make). Anything missing is a failure, not a skip: CI installs node.
# Output: numbered ok/FAIL lines, then "N passed, N failed" as the last line; exit status 1 on any failure.
set -u
root=$(cd "$(dirname "$0")/.." && pwd)
build=${MR_BUILD:-$root/build}
cli=$build/bin/matremap
node_dir=$root/tests/node
tolerance=1e-3
passed=0
failed=0
number=0

report() { # STATUS NAME DETAIL
    number=$((number + 1))
    if [ "$1" = ok ]; then
        passed=$((passed + 1))
        printf '%3d ok    %s  %s\n' "$number" "$2" "$3"
    else
        failed=$((failed + 1))
        printf '%3d FAIL  %s  %s\n' "$number" "$2" "$3"
    fi
}

finish() {
    echo "$passed passed, $failed failed"
    [ "$failed" -eq 0 ] && exit 0
    exit 1
}

# ---- prerequisites (missing = failure) ---------------------------------------------------------------
missing=""
for tool in node npm oiiotool; do
    command -v "$tool" >/dev/null 2>&1 || missing="$missing $tool"
done
if [ -n "$missing" ]; then
    report fail prerequisites "not found:$missing (scripts/install-deps.sh installs them)"
    finish
fi
if [ ! -x "$cli" ]; then
    report fail prerequisites "$cli is not built (run make)"
    finish
fi

work=$(mktemp -d "${TMPDIR:-/tmp}/mr_ssim_crosscheck.XXXXXX")
trap 'rm -rf "$work"' EXIT

if [ ! -f "$node_dir/node_modules/ssim.js/package.json" ] || [ ! -f "$node_dir/node_modules/pngjs/package.json" ]; then
    if ! (cd "$node_dir" && npm ci --no-audit --no-fund --loglevel=error >"$work/npm.log" 2>&1); then
        report fail prerequisites "npm ci in tests/node failed: $(tail -n 3 "$work/npm.log" | tr '\n' ' ')"
        finish
    fi
fi
installed=$(node -p "require('$node_dir/node_modules/ssim.js/package.json').version" 2>/dev/null)
if [ "$installed" != 3.5.0 ]; then
    report fail prerequisites "tests/node has ssim.js '$installed', expected 3.5.0 (delete tests/node/node_modules)"
    finish
fi

# ---- images --------------------------------------------------------------------------------------------
if ! node "$node_dir/ssim_crosscheck.js" generate "$work" 2>"$work/gen.log"; then
    report fail generate "$(tr '\n' ' ' <"$work/gen.log")"
    finish
fi
if ! oiiotool "$work/base.png" --compression jpeg:30 -o "$work/jpeg.jpg" >"$work/oiio.log" 2>&1 ||
    ! oiiotool "$work/jpeg.jpg" -d uint8 -o "$work/jpeg.png" >>"$work/oiio.log" 2>&1; then
    report fail generate "oiiotool: $(tr '\n' ' ' <"$work/oiio.log")"
    finish
fi

# ---- ssim.js -------------------------------------------------------------------------------------------
if ! node "$node_dir/ssim_crosscheck.js" ssim "$work" >"$work/theirs.txt" 2>"$work/theirs.log"; then
    report fail ssim.js "$(tr '\n' ' ' <"$work/theirs.log")"
    finish
fi

# ---- matremap, pair by pair ----------------------------------------------------------------------------
while read -r name a b mode; do
    [ -n "$name" ] || continue
    flags=""
    [ "$mode" != full ] && flags="--downsample"
    # shellcheck disable=SC2086
    json=$("$cli" ssim "$work/$a" "$work/$b" --json $flags 2>"$work/cli.log")
    ours=$(printf '%s\n' "$json" | sed -n 's/.*"ssim": *\([-+0-9.eE]*\).*/\1/p')
    theirs=$(awk -v n="$name" '$1 == n { print $2 }' "$work/theirs.txt")
    if [ -z "$ours" ] || [ -z "$theirs" ]; then
        report fail "$name" "no value (matremap: '${json}' $(tr '\n' ' ' <"$work/cli.log"); ssim.js: '$theirs')"
        continue
    fi
    line=$(awk -v o="$ours" -v t="$theirs" 'BEGIN { d = o - t; if (d < 0) d = -d;
        printf "matremap %.9f  ssim.js %.9f  |diff| %.2e", o, t, d }')
    if [ "$mode" = note ]; then
        echo "    note  $name ($a vs $b, even factor 2, not counted): $line"
        continue
    fi
    if awk -v o="$ours" -v t="$theirs" -v tol="$tolerance" \
        'BEGIN { d = o - t; if (d < 0) d = -d; exit !(d <= tol) }'; then
        report ok "$name" "$line"
    else
        report fail "$name" "$line (tolerance $tolerance)"
    fi
done <"$work/pairs.txt"

# The pairs must span a useful range of SSIM values, or agreement would prove little.
spread=$(awk '$1 != "even_matlab" { if (min == "" || $2 < min) min = $2; if (max == "" || $2 > max) max = $2 }
    END { printf "%.3f..%.3f", min, max; exit !(max - min > 0.3) }' "$work/theirs.txt")
if [ $? -eq 0 ]; then
    report ok spread "SSIM values cover $spread"
else
    report fail spread "SSIM values only cover $spread"
fi

finish

# slopes.awk — the paper's per-roughness specular slopes from sweep rows: for each source roughness, the least-squares
# line through the origin of target specular against source specular (the authors' parametric_remapping.py fits
# k(alpha) to these). Part of `make paper` (scripts/paper-appendix.sh).
#   awk -f cols.awk ... | awk -v sq_src=0 -v sq_tgt=0 -f slopes.awk
# Input lines: "SOURCE_ROUGHNESS SOURCE_SPECULAR TARGET_ROUGHNESS TARGET_SPECULAR", rows of one roughness adjacent.
# Output lines: "ALPHA SLOPE TARGET_ALPHA" in alpha units: sq_src=1 squares the source roughness (Cycles' slider,
# alpha = roughness^2), sq_tgt=1 the target's.
function flush() {
    if (n > 0 && sxx > 0) printf "%.9g %.9g %.9g\n", sq_src ? last * last : last, sxy / sxx, sq_tgt ? ty * ty : ty
    n = 0; sxy = 0; sxx = 0
}
NR > 1 && $1 != last { flush() }
{ sxy += $2 * $4; sxx += $2 * $2; n++; last = $1; ty = $3 }
END { flush() }

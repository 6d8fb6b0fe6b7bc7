# evaluation.sh — what the evaluation scripts share (sourced).
#   env_file NAME                 the shared HDR map called NAME under $assets/hdri: studio (studio_small_03_1k.hdr)
#                                 or tabac (tabac_plant_vogl.hdr)
#   splice_table DOC NAME TABLE   replaces what lies between the lines <!-- NAME:begin --> and <!-- NAME:end --> of
#                                 DOC with the file TABLE (the marker lines stay); returns 1, touching nothing,
#                                 when DOC has no such markers.
env_file() {
    case $1 in
        studio) echo "$assets/hdri/studio_small_03_1k.hdr" ;;
        tabac) echo "$assets/hdri/tabac_plant_vogl.hdr" ;;
    esac
}

splice_table() {
    local doc=$1 name=$2 table=$3
    grep -q "<!-- $name:begin -->" "$doc" 2>/dev/null || return 1
    awk -v table="$table" -v begin="<!-- $name:begin -->" -v end="<!-- $name:end -->" '
        index($0, begin) { print; while ((getline line < table) > 0) print line; skip = 1; next }
        index($0, end) { skip = 0 }
        !skip' "$doc" > "$doc.tmp" && mv "$doc.tmp" "$doc"
}

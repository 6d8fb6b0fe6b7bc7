# docs.sh — what the evaluation scripts share for their documents (sourced).
#   splice_table DOC NAME TABLE   replaces what lies between the lines <!-- NAME:begin --> and <!-- NAME:end --> of
#                                 DOC with the file TABLE (the marker lines stay); returns 1, touching nothing,
#                                 when DOC has no such markers.
splice_table() {
    local doc=$1 name=$2 table=$3
    grep -q "<!-- $name:begin -->" "$doc" 2>/dev/null || return 1
    awk -v table="$table" -v begin="<!-- $name:begin -->" -v end="<!-- $name:end -->" '
        index($0, begin) { print; while ((getline line < table) > 0) print line; skip = 1; next }
        index($0, end) { skip = 0 }
        !skip' "$doc" > "$doc.tmp" && mv "$doc.tmp" "$doc"
}

# doc_section.sh — what the evaluation scripts use to put their tables into the docs (sourced).
#   replace_doc_section DOC NAME FILE   replaces the lines between "<!-- NAME:begin -->" and "<!-- NAME:end -->" in
#                                       DOC with FILE's lines; returns 1 (DOC untouched) when DOC lacks the markers
replace_doc_section() {
    local doc=$1 begin="<!-- $2:begin -->" end="<!-- $2:end -->" file=$3
    grep -qF "$begin" "$doc" 2>/dev/null || return 1
    awk -v file="$file" -v begin="$begin" -v end="$end" '
        $0 == begin { print; while ((getline line < file) > 0) print line; skip = 1; next }
        $0 == end { skip = 0 }
        !skip { print }' "$doc" > "$doc.tmp" && mv "$doc.tmp" "$doc"
}

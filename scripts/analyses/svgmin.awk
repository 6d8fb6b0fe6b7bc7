# svgmin.awk — shrink a gnuplot SVG without changing what it draws (part of `make analyses`):
#   - drops leading indentation and empty groups (<g ...></g>, written for every style change);
#   - merges adjacent groups with identical attributes: gnuplot wraps every point and error bar drawn with a
#     variable colour in its own <g ...> ... </g>; a "</g>" followed by the same "<g ...>" it closed is removed
#     (only when the closed group held no nested group, so the merged children keep their attributes);
#   - in <use> and <path> lines, coordinates to 0.1 px and rgb(r, g, b) colours to #rrggbb.
#   awk -f svgmin.awk in.svg > out.svg
{ sub(/^[ \t]+/, ""); if ($0 ~ /^<(use|path) /) $0 = shorten($0); doc = doc $0 "\n" }
END {
    do { n = gsub(/<g [^<>]*>\n*<\/g>\n?/, "", doc) } while (n > 0)
    m = split(doc, line, "\n")
    depth = 0; pending = ""
    for (i = 1; i <= m; i++) {
        l = line[i]
        if (i == m && l == "") break
        if (l ~ /^<g [^<>]*>$/) {
            if (pending != "" && l == pending) { depth++; open[depth] = l; simple[depth] = 1; pending = ""; continue }
            flush()
            if (depth > 0) simple[depth] = 0
            depth++; open[depth] = l; simple[depth] = 1
            print l
        } else if (l == "</g>") {
            flush()
            if (depth > 0 && simple[depth]) { pending = open[depth]; depth--; continue }
            if (depth > 0) depth--
            print l
        } else {
            flush()
            opens = gsub(/<g[ >]/, "&", l); closes = gsub(/<\/g>/, "&", l)
            for (k = 0; k < closes && depth > 0; k++) depth--
            for (k = 0; k < opens; k++) { if (depth > 0) simple[depth] = 0; depth++; open[depth] = ""; simple[depth] = 0 }
            print l
        }
    }
    flush()
}
function shorten(l,    out, c) {
    out = ""
    while (match(l, /[0-9]+\.[0-9][0-9]+|rgb\( *[0-9]+, *[0-9]+, *[0-9]+\)/)) {
        t = substr(l, RSTART, RLENGTH)
        if (t ~ /^rgb/) { gsub(/[rgb() ]/, "", t); split(t, c, ","); t = sprintf("#%02x%02x%02x", c[1], c[2], c[3]) }
        else t = sprintf("%.1f", t)
        out = out substr(l, 1, RSTART - 1) t
        l = substr(l, RSTART + RLENGTH)
    }
    return out l
}
function flush() { if (pending != "") { print "</g>"; pending = "" } }

# common.gp — settings and outcome colours shared by the make-analyses plots (scripts/analyses.sh).
# The caller sets d (data directory), o (output directory) and h (this directory).
set encoding utf8
set datafile missing 'nan'
set grid lc rgb '#dddddd'
# outcome -> colour: converged green, at-bound orange, unreachable red, local-minimum purple
oc(s) = s eq 'converged' ? 0x1a9850 : s eq 'at-bound' ? 0xf08c00 : s eq 'unreachable' ? 0xd73027 : 0x7b3294
isconv(s) = s eq 'converged'

# Analyses 1 and 3 (paper figures 8 and 10): fitted Ward specular per optimisation strategy, one panel each,
# coloured by outcome, with the RGB spread (min..max over channels) as error bars where it exceeds 0.002; auto
# in grey for reference (five panels: auto, joint, single, two, three).
# Caller sets x (unused label key), pre (file prefix), sfx (file suffix, may be unset), xl, ttl, out.
# Data: d/PRE_STRATEGY SFX.dat: x specular_mean specular_min specular_max outcome ...
load h.'/common.gp'
if (!exists('sfx')) sfx = ''
set terminal svg size 1000,1150 dynamic enhanced font 'Helvetica,12' background rgb 'white'
set output o.'/'.out
set multiplot title ttl font ',14'
set xlabel xl
set ylabel 'fitted Ward specular ρ_{s}, mean of RGB'
set yrange [0:*]
unset key
strategies = 'auto joint single two three'
# An optional overlay: the same strategy with Ward's trimming off (PRE_STRATEGY_trim0.dat) when the driver made it.
# The plot command is assembled per panel and run with eval.
has0 = system('test -f '.d.'/'.pre.'_single_trim0.dat && echo y') eq 'y'
do for [i=1:5] {
    s = word(strategies, i)
    set title sprintf("strategy %s", s)
    set origin ((i - 1) % 2) * 0.5, 0.6 - 0.3 * int((i - 1) / 2)
    set size 0.5, 0.3
    f = d.'/'.pre.'_'.s.sfx.'.dat'
    ov = (i > 2 && has0) ? sprintf("'%s' using 1:2 with lines dt 2 lw 1.5 lc rgb 'black', ", d.'/'.pre.'_'.s.'_trim0.dat') : ''
    eval sprintf("plot '%s' using 1:2 with lines lw 4 lc rgb '#cccccc', ", d.'/'.pre.'_auto'.sfx.'.dat') . ov . \
        sprintf("'%s' using 1:($4 - $3 > 0.002 ? $2 : NaN):3:4:(oc(strcol(5))) with yerrorbars pt 7 ps 0.5 lc rgb variable, ", f) . \
        sprintf("'%s' using 1:($4 - $3 > 0.002 ? NaN : $2):(oc(strcol(5))) with points pt 7 ps 0.5 lc rgb variable, ", f) . \
        sprintf("'%s' using 1:2 with lines lw 0.8 lc rgb '#666666'", f)
}
# the legend, once, in a strip under the title
set origin 0, 0.91
set size 1, 0.05
unset title; unset xlabel; unset ylabel; unset border; unset tics; unset grid
set xrange [0:1]; set yrange [0:1]
set key horizontal center center font ',11' samplen 2 width 1 box
plot NaN with lines lw 4 lc rgb '#cccccc' title 'auto (reference)', \
     NaN with lines dt 2 lw 1.5 lc rgb 'black' title (has0 ? "same strategy, Ward trim=0" : ""), \
     NaN with points pt 7 lc rgb 0x1a9850 title 'converged', NaN with points pt 7 lc rgb 0xf08c00 title 'at-bound', \
     NaN with points pt 7 lc rgb 0xd73027 title 'unreachable', NaN with points pt 7 lc rgb 0x7b3294 title 'local-minimum'
unset multiplot

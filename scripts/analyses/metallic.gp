# Analysis 4 (paper figure 20, Eq. 2): ggx-metallic -> ggx, fitted diffuse and F0 against Eq. 2, and the error map.
# Data: d/a4.dat, one block per albedo: albedo metallic eq2_diffuse fit_diffuse eq2_f0 fit_f0 |err_d| |err_f0|
# fit_alpha outcome rgb_spread.
load h.'/common.gp'
# 1800 scatter points and a 30 x 30 map: a PNG is far smaller than the SVG here.
set terminal pngcairo size 1350,480 enhanced font 'Helvetica,11' background rgb 'white'
set output o.'/metallic_eq2.png'
set multiplot layout 1,3 title "Metallic → specular workflow with GGX (α 0.2, dielectric F_0 0.04), 30 × 30 grid: fits vs paper Eq. 2" font ',14'
set size ratio -1
set xrange [0:1]; set yrange [0:1]
set key top left font ',10' box opaque
set cbrange [0:1]
set palette defined (0 '#2166ac', 0.5 '#f7f7f7', 1 '#b2182b')
set cblabel 'metallic m'
set title 'diffuse'
set xlabel 'Eq. 2: a (1 − m)'
set ylabel 'fitted ggx diffuse'
plot x with lines dt 2 lc rgb 'black' title 'identity', \
     d.'/a4.dat' using 3:4:2 with points pt 7 ps 0.6 lc palette notitle
set title 'specular F_0'
set xlabel 'Eq. 2: 0.04 (1 − m) + m a'
set ylabel 'fitted ggx F_0'
plot x with lines dt 2 lc rgb 'black' title 'identity', \
     d.'/a4.dat' using 5:6:2 with points pt 7 ps 0.6 lc palette notitle
unset key
set title 'max(|Δdiffuse|, |ΔF_0|), log_{10}'
set xlabel 'albedo a'
set ylabel 'metallic m'
set xrange [-0.5/29:1+0.5/29]; set yrange [-0.5/29:1+0.5/29]
set cbrange [-8:-3]
set cblabel 'log_{10} abs error'
set palette defined (0 '#ffffcc', 0.5 '#fd8d3c', 1 '#800026')
plot d.'/a4.dat' using 1:2:(log10(($7 > $8 ? $7 : $8) + 1e-12)) with image notitle
unset multiplot

# Segment-orientation error against the time the segment's markers have been hidden, pooled over
# the 12 occluded simulated cases: every joint's random walk at 8 per second (main at 1364e78)
# against the flexions at 8 and every other joint at 4 (the default since 2026-11-27, 4d8705a).
# Data: scripts/hidden-time-figure.py on docs/benchmarks/accuracy/marker_dependencies_default.json
# and joint_speeds_default.json. Run from the repository root.
set terminal pngcairo size 900,560
set output 'docs/figures/joint_speeds_hidden_time.png'
set title 'Segment error against time hidden: one joint speed against two (paper occlusion, 12 cases)'
set xlabel 'time since the segment last showed all its markers'; set ylabel 'RMS error (deg)'
set grid; set key left top; set yrange [0:*]
set xtics ('visible' 0, '<= 0.1 s' 1, '0.1-0.25' 2, '0.25-0.5' 3, '0.5-1' 4, '1-2' 5, '> 2 s' 6)
u = 'docs/benchmarks/joint_speeds_hidden_time_uniform.dat'
d = 'docs/benchmarks/joint_speeds_hidden_time_default.dat'
plot u u 1:4 w lp lw 3 pt 7 lc rgb 'gray50' t 'all segments, 8 for every joint', \
     d u 1:4 w lp lw 3 pt 7 lc rgb 'black' t 'all segments, 8 flexion / 4 other', \
     d u 1:11 w lp lw 2 pt 6 dt 2 lc rgb 'black' t 'all segments, 8 / 4, --smooth', \
     u u 1:6 w lp lw 1.5 pt 9 lc rgb '#e08080' t 'hands, 8 for every joint', \
     d u 1:6 w lp lw 1.5 pt 9 lc rgb '#c00000' t 'hands, 8 / 4', \
     u u 1:5 w lp lw 1.5 pt 5 lc rgb '#8080e0' t 'forearms, 8 for every joint', \
     d u 1:5 w lp lw 1.5 pt 5 lc rgb '#0000c0' t 'forearms, 8 / 4'

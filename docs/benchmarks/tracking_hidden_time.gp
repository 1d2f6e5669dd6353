# Segment-orientation error against the time the segment's markers have been hidden (at least one
# of them), pooled over the occluded cases of the accuracy table. Data: scripts/hidden-time-figure.py.
set terminal pngcairo size 900,560
set output 'docs/figures/tracking_hidden_time.png'  # run from the repository root
set title 'Segment orientation error against time hidden (paper occlusion, 12 simulated cases)'
set xlabel 'time since the segment last showed all its markers'; set ylabel 'RMS error (deg)'
set grid; set key left top; set yrange [0:*]
set xtics ('visible' 0, '<= 0.1 s' 1, '0.1-0.25' 2, '0.25-0.5' 3, '0.5-1' 4, '1-2' 5, '> 2 s' 6)
f = 'docs/benchmarks/tracking_hidden_time.dat'
plot f u 1:4 w lp lw 3 pt 7 lc rgb 'black' t 'all segments, filter', \
     f u 1:11 w lp lw 3 pt 6 dt 2 lc rgb 'black' t 'all segments, --smooth', \
     f u 1:5 w lp lw 1.5 pt 5 t 'forearms', \
     f u 1:6 w lp lw 1.5 pt 9 t 'hands', \
     f u 1:7 w lp lw 1.5 pt 11 t 'feet', \
     f u 1:8 w lp lw 1.5 pt 13 t 'shanks', \
     f u 1:9 w lp lw 1.5 pt 3 t 'thighs', \
     f u 1:10 w lp lw 1.5 pt 1 lc rgb 'gray50' t 'trunk and pelvis'

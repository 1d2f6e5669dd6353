# The ladder of references behind the tracker's accuracy, and the static-trial calibration, on the
# 12 simulated realistic cases of seeds 1-3 without occlusion. Data: docs/benchmarks/accuracy_ladder.dat
# (from scripts/accuracy-ladder.py and scripts/static-trial-table.py). Run from the repository root.
set terminal pngcairo size 1000,600
set output 'docs/figures/accuracy_ladder.png'
set title "Accuracy by subject model, 12 simulated cases without occlusion\n(\"fit\": per-frame fit started at the true pose)" 
set ylabel 'RMS error (deg)'; set grid ytics; set yrange [0:10]
set style data histograms; set style histogram clustered gap 1; set style fill solid 0.8 border -1
set boxwidth 0.9; set xtics rotate by 30 right font ',10'; set key right top; set bmargin 9
set arrow from graph 0, first 4 to graph 1, first 4 nohead dt 2 lc rgb 'black'
set label 'segment target (4 deg)' at graph 0.99, first 4.25 right font ',9'
f = 'docs/benchmarks/accuracy_ladder.dat'
plot f u 2:xtic(1) t 'segment orientation' lc rgb '#4477aa', \
     '' u 3 t 'limb flexion' lc rgb '#ee6677', \
     '' u 4 t 'root orientation' lc rgb '#228833'

set terminal pngcairo size 900,560
set output 'docs/figures/track_step_latency.png'  # run from the repository root
set title 'S2KF tracking step (handstand, 46 states) vs sample count L, median per frame'
set xlabel 'sample count L'; set ylabel 'time per frame (µs)'
set logscale xy; set grid; set key left top
set xtics (93,201,301,461,1001); set xrange [85:1100]
plot 'docs/benchmarks/track_step_latency.dat' index 0 u 1:2 w lp lw 2 pt 7 t 'step, 50 markers, portable', \
     'docs/benchmarks/track_step_latency.dat' index 0 u 1:3 w l dt 2 lw 2 t 'floor, 50 markers, portable', \
     'docs/benchmarks/track_step_latency.dat' index 0 u 1:4 w lp lw 2 pt 5 t 'step, 50 markers, -march=native', \
     'docs/benchmarks/track_step_latency.dat' index 1 u 1:2 w lp lw 2 pt 6 t 'step, 34 markers, portable', \
     'docs/benchmarks/track_step_latency.dat' index 1 u 1:3 w l dt 3 lw 2 t 'floor, 34 markers, portable', \
     'docs/benchmarks/track_step_latency.dat' index 1 u 1:4 w lp lw 2 pt 4 t 'step, 34 markers, -march=native', \
     250 w l lc rgb 'red' t '0.25 ms target'

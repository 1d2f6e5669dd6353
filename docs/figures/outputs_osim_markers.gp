# Run from the repository root: build/s2kf model --height 1750 > /tmp/s2kf_markers.csv && gnuplot -e "markers='/tmp/s2kf_markers.csv'" docs/figures/outputs_osim_markers.gp
# The markers of the body model at the zero pose (subject height 1750 mm), as the OpenSim model
# (.osim) carries them on its bodies: front view (x right, z up) and side view (y forward, z up),
# in mm from the pelvis joint. The figure in docs/outputs.md.
if (!exists("markers")) markers = 'markers.csv'
# Right-side markers (names starting with R) are labelled below their point, the others above, so
# that the left and right markers that coincide in the side view both stay readable.
right(name) = substr(name, 1, 1) eq 'R' ? name : ''
other(name) = substr(name, 1, 1) eq 'R' ? '' : name
set terminal pngcairo size 1400,1000 font "Sans,10"
set output 'docs/figures/outputs_osim_markers.png'
set datafile separator ','
set key off
set grid
set size ratio -1
set multiplot layout 1,2 title "s2kf model --height 1750: the 50 model markers at the zero pose (mm, from the pelvis joint)"
set title 'front (from the front: subject right on the left)'
set xlabel 'x (mm, subject right +)'
set ylabel 'z (mm, up)'
set xrange [400:-400]
set yrange [-950:830]
plot markers every ::1 using 2:4 with points pt 7 ps 1 lc rgb '#1f5fbf', \
     markers every ::1 using 2:4:(other(strcol(1))) with labels font ',7' offset 0,0.6 tc rgb '#333333', \
     markers every ::1 using 2:4:(right(strcol(1))) with labels font ',7' offset 0,-0.6 tc rgb '#8b0000'
set title 'side (from the subject right: forward to the right)'
set xlabel 'y (mm, forward +)'
set ylabel 'z (mm, up)'
set xrange [-300:300]
plot markers every ::1 using 3:4 with points pt 7 ps 1 lc rgb '#bf3f1f', \
     markers every ::1 using 3:4:(other(strcol(1))) with labels font ',7' offset 0,0.6 tc rgb '#333333', \
     markers every ::1 using 3:4:(right(strcol(1))) with labels font ',7' offset 0,-0.6 tc rgb '#8b0000'
unset multiplot

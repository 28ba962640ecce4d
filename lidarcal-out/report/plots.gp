set terminal pngcairo size 1000,650 font "DejaVu Sans,11"
set grid
set key outside below horizontal
set xrange [0.255152:4.4728]
fit_min = 0.606623
fit_max = 4.12133
label_every = 1
set arrow 1 from fit_min, graph 0 to fit_min, graph 1 nohead dt 3 lc rgb "#666666"
set arrow 2 from fit_max, graph 0 to fit_max, graph 1 nohead dt 3 lc rgb "#666666"
set output "distance.png"
set title "Raw range error against the distance estimated from the landmarks (dotted: fitted range)"
set xlabel "estimated true distance d [m]"
set ylabel "raw reading - d [m]"
plot "distance.dat" using 1:($2-$1) with points pt 7 ps 0.3 lc rgb "#8899bb" title "readings on landmarks", \
     "curve.dat" using 1:($2-$1) with lines lw 2 lc rgb "#cc3311" title "fitted bias f(d) - d", \
     0 with lines dt 2 lc rgb "black" title "ideal (no error)"
set output "residuals.png"
set title "Error before and after correction against the estimated distance"
set ylabel "reading - d [mm]"
plot "distance.dat" using 1:(1000*($2-$1)) with points pt 7 ps 0.3 lc rgb "#cc3311" title "raw", \
     "distance.dat" using 1:(1000*($3-$1)) with points pt 7 ps 0.3 lc rgb "#009944" title "corrected", \
     0 with lines dt 2 lc rgb "black" title "no error"
set output "noise.png"
set title "Noise against distance"
set ylabel "standard deviation of the reading [mm]"
plot "noise.dat" using 1:($2*1000) with points pt 7 ps 1 lc rgb "#0077bb" title "measured (RMS residual, 0.25 m bins)", \
     "noise.dat" using 1:($3*1000) with lines lw 2 lc rgb "#cc3311" title "noise model"
unset arrow 1
unset arrow 2
set output "histogram.png"
set title "Error of the readings on landmarks, before and after correction"
set autoscale x
set xlabel "reading - estimated distance [mm]"
set ylabel "readings"
plot "histogram.dat" using (1000*$1):2 with histeps lw 2 lc rgb "#cc3311" title "raw", \
     "histogram.dat" using (1000*$1):3 with histeps lw 2 lc rgb "#009944" title "corrected"
set terminal pngcairo size 900,900 font "DejaVu Sans,11"
set output "map.png"
set title "Landmarks with raw and corrected points, one scan per stop"
set autoscale x
set xlabel "x [m]"
set ylabel "y [m]"
set size ratio -1
plot "circles.dat" using 1:2 with lines lw 2 lc rgb "#999999" title "landmarks (estimated)", \
     "truth.dat" using 1:2 with lines lw 1 dt 2 lc rgb "black" title "landmarks (truth)", \
     "raw.dat" using 1:2 with points pt 2 ps 0.6 lc rgb "#cc3311" title "raw", \
     "corrected.dat" using 1:2 with points pt 6 ps 0.6 lc rgb "#009944" title "corrected", \
     "stops.dat" using 1:2 with points pt 7 ps 0.8 lc rgb "#0044aa" title "stops (numbered)", \
     "stops.dat" using 1:2:(int($3) % label_every == 0 ? sprintf("%d", $3) : "") with labels offset 0.8,0.8 font ",9" tc rgb "#0044aa" notitle

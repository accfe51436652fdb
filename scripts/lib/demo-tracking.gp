# The demo's picture: measured output against the reference over the scored periods of a 1 Hz
# triangle, without compensation and through the identified model's inverse.
# gnuplot -e "none='A.csv'; inverse='B.csv'; out='tracking.png'" demo-tracking.gp
set terminal pngcairo size 640,600 font ",11"
set output out
set datafile separator ","
set datafile commentschars "#"
set key bottom right
set grid
set size ratio -1
set xlabel "reference yr [um]"
set ylabel "measured y [um]"
set title "1 Hz triangle over 80 % of the range"
# columns: index,t,t_scheduled_ns,t_wake_ns,exec_ns,yr,u_ff,u_fb,u,y,y_model,flags;
# the first second (precondition and first period) is left out
plot none using ($2 > 2 ? $6 : 1/0):10 every 10 with lines lw 2 title "no compensation", \
     inverse using ($2 > 2 ? $6 : 1/0):10 every 10 with lines lw 2 title "inverse model (feedforward)", \
     x with lines dt 2 lc rgb "black" title "ideal"

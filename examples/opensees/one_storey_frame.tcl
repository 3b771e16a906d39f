# The paper's one-storey frame in OpenSees (Tcl), its column served by rths through genericClient.
# First start the site:   rths opensees-site examples/opensees/site_paper_frame.textproto --port 8090
# then:                   OpenSees examples/opensees/one_storey_frame.tcl
# Units: m, kg, N, s. Floor displacement to frame_disp.out.
wipe
model basic -ndm 1 -ndf 1
set T 0.5
set m 1000.0
set pi [expr {acos(-1.0)}]
set omega [expr {2.0 * $pi / $T}]
set k [expr {$m * $omega * $omega}]
set fraction 0.3333333333333333
node 1 0.0
node 2 0.0 -mass $m
fix 1 1
# Two thirds of the storey: the numerical columns.
uniaxialMaterial Elastic 1 [expr {(1.0 - $fraction) * $k}]
element zeroLength 1 1 2 -mat 1 -dir 1
# A third: the specimen column, served by rths (one actuator on u2 - u1).
element genericClient 2 -node 1 2 -dof 1 -dof 1 -server 8090 127.0.0.1 -dataSize 256
# 5 % of critical, mass proportional (c = 2 zeta omega m).
rayleigh [expr {2.0 * 0.05 * $omega}] 0.0 0.0 0.0

# The PEER AT2 record (g) as a one-column file for timeSeries Path.
proc read_at2 {in out} {
  set f [open $in r]
  for {set i 0} {$i < 3} {incr i} { gets $f }
  gets $f header
  regexp {DT=\s*([0-9.Ee+-]+)} $header -> dt
  set values [read $f]
  close $f
  set o [open $out w]
  foreach v $values { puts $o $v }
  close $o
  return $dt
}
set here [file dirname [info script]]
set dt_record [read_at2 [file join $here ../../data/ground_motions/RSN175_IMPVALL.H_H-E12140.AT2] elcentro.g]
timeSeries Path 1 -dt $dt_record -filePath elcentro.g -factor 9.81
pattern UniformExcitation 1 1 -accel 1

recorder Node -file frame_disp.out -time -node 2 -dof 1 disp
constraints Plain
numberer Plain
system FullGeneral
algorithm Linear
# Explicit: one trial per step, which is what an actuator can follow.
integrator NewmarkExplicit 0.5
analysis Transient
set dt 0.001
analyze 15000 $dt
# genericClient tells the site it is done (action 99) when its element is destroyed.
wipe

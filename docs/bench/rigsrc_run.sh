#!/bin/bash
# Bakes a small demo grid (indirect only) and runs probekit rig per rig type.
set -e
B=${PROBEKIT:-target/debug/probekit}
B=$(realpath "$B")
mkdir -p /tmp/rigsrc && cd /tmp/rigsrc
if [ ! -f demo_ind.probes ]; then
  /usr/bin/time -f "bake %e s" $B bake builtin:demo --grid 128 --samples 256 --indirect-only -o demo_ind.probes --json
fi
$B inspect demo_ind.probes --json | head -c 300; echo
AT=6.07,0,2.0
for split in off on; do
for r in constant gradient lattice:2x2x3 lattice:3x2x2 mixed:l3,g,c mixed:l3,g,g lattice:8x4x2; do
  echo "A split=$split $r $($B rig builtin:car --scene builtin:demo --probes demo_ind.probes --rig $r --at $AT --split $split --json 2>/tmp/rigsrc/warn.txt)"
done
done
for r in constant gradient lattice:2x2x3 lattice:3x2x2 mixed:l3,g,c mixed:l3,g,g lattice:8x4x2; do
  echo "B $r $($B rig builtin:car --probes demo_ind.probes --rig $r --at $AT --split off --json)"
done
cat /tmp/rigsrc/warn.txt
$B rig builtin:car --scene builtin:demo --probes demo_ind.probes --rig mixed:l3,g,c --at $AT

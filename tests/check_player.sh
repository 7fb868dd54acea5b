#!/bin/sh
# check_player.sh XMIN XMAX YMIN YMAX ZMIN ZMAX COMMAND...: runs COMMAND, finds its last
# "player: feet X Y Z ..." line and fails unless X, Y, Z lie in the given ranges, the player is on the
# ground, and no validation message was printed.
xmin=$1 xmax=$2 ymin=$3 ymax=$4 zmin=$5 zmax=$6
shift 6
out=$("$@" 2>&1)
rc=$?
printf '%s\n' "$out"
[ $rc -eq 0 ] || { echo "check_player: command failed ($rc)"; exit 1; }
if printf '%s\n' "$out" | grep -q '\[vulkan\]'; then echo "check_player: validation message"; exit 1; fi
line=$(printf '%s\n' "$out" | grep '^player: feet' | tail -1)
[ -n "$line" ] || { echo "check_player: no 'player:' line"; exit 1; }
echo "$line" | awk -v x0="$xmin" -v x1="$xmax" -v y0="$ymin" -v y1="$ymax" -v z0="$zmin" -v z1="$zmax" '{
  x = $3; y = $4; z = $5
  if (x < x0 || x > x1) { print "check_player: x " x " not in [" x0 ", " x1 "]"; exit 1 }
  if (y < y0 || y > y1) { print "check_player: y " y " not in [" y0 ", " y1 "]"; exit 1 }
  if (z < z0 || z > z1) { print "check_player: z " z " not in [" z0 ", " z1 "]"; exit 1 }
  if ($0 !~ /grounded/) { print "check_player: not on the ground"; exit 1 }
  print "check_player: ok"
}'

#!/usr/bin/env bash
# ctest "slurm": a one-node Slurm cluster from Debian's packages (munge, slurmctld, slurmd; loopback only;
# every file in a temp dir; daemons stopped at the end even on failure) runs scripts/farm/slurm_array.sh:
# an array job renders a 4x4 grid of tiles (3 tiles per task: 6 tasks), a dependent job stitches them with
# `stex assemble`, and the result must equal a single-process render bit for bit. Then two tiles are
# deleted and the same command resubmitted: exactly those two are rendered again, every other tile file is
# untouched, and the new assembly is again identical.
#
# The renderer is the real `stex render` (texton noise on the default OpenCL device), or, where no device
# exists, tests/farm/helper/farm_synth (the same farm options over a synthetic pattern).
# Usage: slurm_test.sh FARM_SYNTH STEX TMPDIR. Exit 77 (ctest: skipped) when not root, except under CI
# (CI=true), where not running it is a failure.
set -euo pipefail

SYNTH=$1 STEX_BIN=$2 T=$3
HERE=$(cd "$(dirname "$0")" && pwd)
SRC=$(cd "$HERE/../.." && pwd)
start=$(date +%s.%N)

if [ "$(id -u)" -ne 0 ]; then
  if [ "${CI:-}" = true ]; then
    echo "FAIL: the Slurm test needs root (it runs slurmctld/slurmd as root) and CI must run it"
    exit 1
  fi
  echo "SKIP: the Slurm test needs root (it installs munge/slurm and runs slurmctld/slurmd as root)"
  exit 77
fi
pkgs=(munge slurmctld slurmd slurm-client)
missing=()
for p in "${pkgs[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "slurm test: installing ${missing[*]}"
  export DEBIAN_FRONTEND=noninteractive
  apt-get update -qq
  apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi

rm -rf "$T"
mkdir -p "$T/munge" "$T/state" "$T/spool" "$T/log" "$T/work"
chmod 700 "$T/munge"
stop_daemons() {
  local f p
  for f in slurmd slurmctld munge/munged; do
    p=$(cat "$T/$f.pid" 2>/dev/null || true)
    if [ -n "$p" ] && kill -0 "$p" 2>/dev/null; then kill "$p" 2>/dev/null || true; fi
  done
  for f in slurmd slurmctld munge/munged; do  # wait up to 10 s for each to exit
    p=$(cat "$T/$f.pid" 2>/dev/null || true)
    for _ in $(seq 100); do { [ -z "$p" ] || ! kill -0 "$p" 2>/dev/null; } && break; sleep 0.1; done
  done
}
on_exit() {
  rc=$?
  stop_daemons
  if [ $rc -ne 0 ]; then
    echo "slurm test FAILED (exit $rc); logs:"
    tail -n 20 "$T"/log/*.log "$T"/work/slurm-logs/*.log 2>/dev/null || true
  fi
  exit $rc
}
trap on_exit EXIT

# munge with a private key and socket.
head -c 1024 /dev/urandom > "$T/munge/munge.key"
chmod 400 "$T/munge/munge.key"
munged -f --key-file="$T/munge/munge.key" --socket="$T/munge/munge.socket.2" --pid-file="$T/munge/munged.pid" \
  --log-file="$T/munge/munged.log" --seed-file="$T/munge/munged.seed"

# Private ports (two test runs on one machine must not meet), loopback only.
port=$(( 20000 + ($$ % 5000) * 2 ))
H=$(hostname)
cat > "$T/slurm.conf" <<EOF
ClusterName=stextest
SlurmctldHost=$H(127.0.0.1)
SlurmUser=root
SlurmdUser=root
SlurmctldPort=$port
SlurmdPort=$((port + 1))
AuthType=auth/munge
AuthInfo=socket=$T/munge/munge.socket.2
CredType=cred/munge
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
StateSaveLocation=$T/state
SlurmdSpoolDir=$T/spool
SlurmctldPidFile=$T/slurmctld.pid
SlurmdPidFile=$T/slurmd.pid
SlurmctldLogFile=$T/log/slurmctld.log
SlurmdLogFile=$T/log/slurmd.log
ReturnToService=2
MpiDefault=none
NodeName=$H NodeAddr=127.0.0.1 CPUs=$(nproc) RealMemory=1000 State=UNKNOWN
PartitionName=stextest Nodes=ALL Default=YES MaxTime=INFINITE State=UP
EOF
export SLURM_CONF="$T/slurm.conf"
slurmctld -c -f "$SLURM_CONF"
slurmd -f "$SLURM_CONF"
for _ in $(seq 150); do
  sinfo -h -o '%t' 2>/dev/null | grep -q idle && break
  sleep 0.2
done
sinfo -h -o '%t' | grep -q idle || { echo "slurm test: the node never became idle"; sinfo || true; exit 1; }
cluster_up=$(date +%s.%N)

cd "$T/work"
# The renderer: the real `stex render` (texton noise on the default OpenCL device) with a model analysed
# from a small noise exemplar; the synthetic farm_synth when no OpenCL device is available (exit 4).
# The single-process reference render runs first, which also warms the PoCL kernel cache that the
# concurrent tasks then only read (docs/farm.md: PoCL's cache is not safe against concurrent writers).
export POCL_CACHE_DIR="$T/pocl-cache"
SIZE=1000x800 TILE=256 PER_TASK=3  # 4x4 = 16 tiles, 6 tasks
"$SYNTH" -o "$T/work/exemplar.png" --size 64x64 --progress none -q
"$STEX_BIN" analyze "$T/work/exemplar.png" -o "$T/work/model.stex" --support 16 --iterations 3 -q
export STEX="$STEX_BIN" STEX_RENDER="$STEX_BIN render"
set +e
$STEX_RENDER "$T/work/model.stex" -o "$T/work/single.exr" --size $SIZE --tile-size $TILE --seed 9 --progress none -q
rc=$?
set -e
if [ $rc = 4 ]; then
  echo "slurm test: no OpenCL device for stex render: using the synthetic renderer"
  export STEX_RENDER="$SYNTH"
  $STEX_RENDER "$T/work/model.stex" -o "$T/work/single.exr" --size $SIZE --tile-size $TILE --seed 9 --progress none
elif [ $rc != 0 ]; then
  echo "slurm test: the single-process render failed (exit $rc)"
  exit 1
fi
echo "slurm test: renderer: $STEX_RENDER"
submit() {
  "$SRC/scripts/farm/slurm_array.sh" --model "$T/work/model.stex" --size $SIZE --tile-size $TILE \
    --tiles-per-task $PER_TASK --tiles "$T/work/tiles/t_{tx}_{ty}.exr" --output "$T/work/out/texture.exr" \
    --parallel 2 --wait -- --seed 9
}
ids=$(submit)
array_id=${ids%% *}
"$SYNTH" --check-equal "$T/work/out/texture.exr" "$T/work/single.exr" ||
  { echo "slurm test: the assembled texture differs from the single-process render"; exit 1; }
ntiles=$(ls "$T"/work/tiles/t_*.exr | wc -l)
[ "$ntiles" = 16 ] || { echo "slurm test: $ntiles tiles instead of 16"; exit 1; }
first_run=$(date +%s.%N)

# Resubmit after deleting two tiles: only those two are rendered again.
stat -c '%n %i %Y' "$T"/work/tiles/t_*.exr | sort > "$T/before.txt"
rm "$T/work/tiles/t_1_0.exr" "$T/work/tiles/t_2_3.exr"
rm "$T/work/out/texture.exr"
ids=$(submit)
array_id2=${ids%% *}
[ "$array_id2" != "$array_id" ] || { echo "slurm test: no new array job"; exit 1; }
logs="$T/work/out/slurm-logs"
rendered=$(cat "$logs"/tiles_"${array_id2}"_*.log | grep -c '^stex: tile [0-9]* done ' || true)
skipped=$(cat "$logs"/tiles_"${array_id2}"_*.log | grep -c '^stex: tile [0-9]* skipped ' || true)
redone=$(cat "$logs"/tiles_"${array_id2}"_*.log | grep '^stex: tile [0-9]* done ' | sed 's/.*: //' | sort | tr '\n' ' ')
echo "slurm test: resubmission rendered $rendered tile(s) ($redone), skipped $skipped"
[ "$rendered" = 2 ] && [ "$skipped" = 14 ] || { echo "slurm test: expected 2 rendered and 14 skipped"; exit 1; }
[ "$redone" = "$T/work/tiles/t_1_0.exr $T/work/tiles/t_2_3.exr " ] ||
  { echo "slurm test: the wrong tiles were rendered again: $redone"; exit 1; }
stat -c '%n %i %Y' "$T"/work/tiles/t_*.exr | sort > "$T/after.txt"
changed=$(diff "$T/before.txt" "$T/after.txt" | grep -c '^>' || true)
[ "$changed" = 2 ] || { echo "slurm test: $changed tile files changed instead of 2"; diff "$T/before.txt" "$T/after.txt"; exit 1; }
"$SYNTH" --check-equal "$T/work/out/texture.exr" "$T/work/single.exr" ||
  { echo "slurm test: the re-assembled texture differs from the single-process render"; exit 1; }

end=$(date +%s.%N)
awk -v s="$start" -v u="$cluster_up" -v f="$first_run" -v e="$end" 'BEGIN {
  printf "slurm test: PASSED in %.1f s (cluster start %.1f s, reference render + array job + assemble %.1f s, resubmission %.1f s)\n",
         e - s, u - s, f - u, e - f }'

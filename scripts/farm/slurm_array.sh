#!/usr/bin/env bash
# Renders a stex texture on a Slurm cluster in one command: an array job renders the tiles (each task
# takes its task id from SLURM_ARRAY_TASK_ID and renders --tiles-per-task tiles, resuming with
# --skip-existing), then a dependent job stitches them with `stex assemble` into one tiled EXR/TIFF.
# See docs/farm.md.
#
#   scripts/farm/slurm_array.sh --model gravel.stex --size 65536x65536 --tile-size 4096 \
#       --tiles-per-task 4 --tiles 'out/gravel_{tx}_{ty}.exr' --output out/gravel.exr [--parallel 32] \
#       [--wait] [--sbatch "--partition=render --time=01:00:00"] [-- more `stex render` options]
#
# Environment: STEX (the stex binary, default `stex` on PATH); STEX_RENDER (the render command, default
# "$STEX render"; the tests put a synthetic renderer with the same farm options here).
# Resubmitting the same command renders only the tiles that are missing or invalid (--skip-existing).
# Exit codes: 0 submitted (with --wait: the texture is assembled); 2 usage; otherwise sbatch's / the
# assemble job's code (docs/farm.md has the table).
set -euo pipefail

STEX=${STEX:-stex}
STEX_RENDER=${STEX_RENDER:-"$STEX render"}

usage() {
  sed -n '2,17p' "$0" | sed 's/^# \{0,1\}//' >&2
  exit 2
}

role=submit model="" size="" tile_size="" per_task=1 tiles="" output="" parallel=16 wait=0 sbatch_extra=""
extra=()
while [ $# -gt 0 ]; do
  case "$1" in
    --role) role=$2; shift 2 ;;
    --model) model=$2; shift 2 ;;
    --size) size=$2; shift 2 ;;
    --tile-size) tile_size=$2; shift 2 ;;
    --tiles-per-task) per_task=$2; shift 2 ;;
    --tiles) tiles=$2; shift 2 ;;
    --output) output=$2; shift 2 ;;
    --parallel) parallel=$2; shift 2 ;;
    --sbatch) sbatch_extra=$2; shift 2 ;;
    --wait) wait=1; shift ;;
    --) shift; extra=("$@"); break ;;
    -h|--help) usage ;;
    *) echo "slurm_array.sh: unknown argument '$1'" >&2; usage ;;
  esac
done

case "$role" in
  render)
    # One array task. The task id comes from SLURM_ARRAY_TASK_ID (read by stex itself).
    # PoCL's on-disk kernel cache is not safe against concurrent writers (docs/farm.md; tasks on one node,
    # or a home directory shared by nodes): unless the user set POCL_CACHE_DIR, each task gets its own
    # under the node-local temp dir (a cold kernel build costs ~1 s per task; a tile costs more).
    if [ -z "${POCL_CACHE_DIR:-}" ]; then
      own_cache="${TMPDIR:-/tmp}/stex-pocl-${SLURM_ARRAY_JOB_ID:-0}-${SLURM_ARRAY_TASK_ID:-0}"
      export POCL_CACHE_DIR="$own_cache"
      # Slurm signals every process of the step, so stex stops at a tile boundary (exit 130) and the
      # cache is removed here either way.
      trap 'rm -rf "$own_cache"' EXIT
      # shellcheck disable=SC2086
      $STEX_RENDER "$model" -o "$tiles" --size "$size" --tile-size "$tile_size" \
        --tiles-per-task "$per_task" --skip-existing --progress lines "${extra[@]}"
      exit $?
    fi
    # shellcheck disable=SC2086
    exec $STEX_RENDER "$model" -o "$tiles" --size "$size" --tile-size "$tile_size" \
      --tiles-per-task "$per_task" --skip-existing --progress lines "${extra[@]}"
    ;;
  assemble)
    exec "$STEX" assemble --template "$tiles" -o "$output"
    ;;
  submit) ;;
  *) echo "slurm_array.sh: unknown role '$role'" >&2; exit 2 ;;
esac

for v in model size tile_size tiles output; do
  [ -n "${!v}" ] || { echo "slurm_array.sh: --${v//_/-} is required" >&2; usage; }
done
[[ "$size" =~ ^([0-9]+)[xX]([0-9]+)$ ]] || { echo "slurm_array.sh: --size must be WxH" >&2; exit 2; }
w=${BASH_REMATCH[1]} h=${BASH_REMATCH[2]}
[[ "$tile_size" =~ ^[1-9][0-9]*$ && "$per_task" =~ ^[1-9][0-9]*$ && "$parallel" =~ ^[1-9][0-9]*$ ]] ||
  { echo "slurm_array.sh: --tile-size, --tiles-per-task and --parallel must be positive integers" >&2; exit 2; }
nx=$(( (w + tile_size - 1) / tile_size )) ny=$(( (h + tile_size - 1) / tile_size ))
tasks=$(( (nx * ny + per_task - 1) / per_task ))
mkdir -p "$(dirname "$tiles")" "$(dirname "$output")"
logs="$(dirname "$output")/slurm-logs"
mkdir -p "$logs"

common=(--model "$model" --size "$size" --tile-size "$tile_size" --tiles-per-task "$per_task"
        --tiles "$tiles" --output "$output")
# shellcheck disable=SC2086
array_id=$(sbatch --parsable $sbatch_extra --job-name=stex-tiles --array="0-$((tasks - 1))%$parallel" \
  --output="$logs/tiles_%A_%a.log" "$0" --role render "${common[@]}" -- "${extra[@]}")
array_id=${array_id%%;*}
echo "slurm_array.sh: $((nx * ny)) tiles (${nx}x${ny} of $tile_size px) in $tasks task(s): array job $array_id" >&2
# shellcheck disable=SC2086
assemble_id=$(sbatch --parsable $sbatch_extra --job-name=stex-assemble \
  --dependency="afterok:$array_id" --kill-on-invalid-dep=yes --output="$logs/assemble_%j.log" \
  "$0" --role assemble "${common[@]}")
assemble_id=${assemble_id%%;*}
echo "slurm_array.sh: assemble job $assemble_id -> $output (logs in $logs)" >&2
echo "$array_id $assemble_id"
[ "$wait" = 1 ] || exit 0

# --wait: poll the assemble job once a second (sbatch --wait backs off to 30 s between polls).
job_field() { scontrol show job "$1" -o 2>/dev/null | tr ' ' '\n' | sed -n "s/^$2=//p" | head -n 1; }
while :; do
  state=$(job_field "$assemble_id" JobState)
  case "$state" in
    COMPLETED) exit 0 ;;
    PENDING|CONFIGURING|RUNNING|COMPLETING|SUSPENDED|REQUEUED|RESIZING|"") sleep 1 ;;
    *)
      code=$(job_field "$assemble_id" ExitCode)
      echo "slurm_array.sh: assemble job $assemble_id ended $state (exit ${code:-?}); tile logs: $logs" >&2
      code=${code%%:*}
      [ -n "$code" ] && [ "$code" != 0 ] && exit "$code"
      # Cancelled because a tile task failed: report the highest tile exit code (docs/farm.md).
      worst=$(scontrol show job "$array_id" -o 2>/dev/null | tr ' ' '\n' | sed -n 's/^ExitCode=\([0-9]*\):.*/\1/p' |
              sort -n | tail -n 1)
      exit "${worst:-1}"
      ;;
  esac
done

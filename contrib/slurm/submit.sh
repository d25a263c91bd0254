#!/usr/bin/env bash
# Render one whitted image over a Slurm array job, then merge the parts.
#
#   contrib/slurm/submit.sh [--wait] SCENE OUTDIR N [whitted render options]
#
# Submits an array job of N tasks, task I rendering `--tile I/N` of SCENE (a built-in scene
# name or a .toml file) into OUTDIR/NAME.tile-I-of-N.exr, and a merge job that runs once
# every task has succeeded (--dependency=afterok) and writes OUTDIR/NAME.exr, NAME being the
# scene's name. Prints the two job ids. With --wait it returns when the merge job has ended,
# with its exit status (non-zero too when a task failed and the merge was cancelled).
# The render options (e.g. --width 7680 --height 4320 --depth 6 --half) go to every task;
# the part and the output name are the script's to choose, so -o, --tile, --crop and
# --pixel-bounds are refused. Task logs: OUTDIR/slurm-JOB_TASK.out.
#
# The whitted binary: $WHITTED, else `whitted` on PATH, else this checkout's
# target/release/whitted. It, SCENE, the scene's files and OUTDIR must be reachable at the
# same paths from every node (a shared file system); the environment (WHITTED_ASSETS too)
# is passed on to the jobs (sbatch's default --export=ALL). Extra sbatch options:
# $SBATCH_OPTS (e.g. "--partition=big --time=1:00:00"), given to both jobs.
set -euo pipefail

die() {
    echo "submit.sh: $*" >&2
    exit 2
}

# --- inside a job: the two halves of the work (submit.sh submits itself as the job script)
if [[ ${1:-} == --task-render ]]; then
    shift
    whitted=$1 scene=$2 outdir=$3 name=$4 n=$5
    shift 5
    i=${SLURM_ARRAY_TASK_ID:?not inside a Slurm array job}
    exec "$whitted" render "$scene" --tile "$i/$n" -q -o "$outdir/$name.tile-$i-of-$n.exr" "$@"
fi
if [[ ${1:-} == --task-merge ]]; then
    shift
    whitted=$1 outdir=$2 name=$3 n=$4
    parts=()
    for ((i = 0; i < n; i++)); do parts+=("$outdir/$name.tile-$i-of-$n.exr"); done
    exec "$whitted" merge "${parts[@]}" -o "$outdir/$name.exr"
fi

# --- on the submitting host
wait=0
if [[ ${1:-} == --wait ]]; then
    wait=1
    shift
fi
[[ $# -ge 3 ]] || die "usage: submit.sh [--wait] SCENE OUTDIR N [whitted render options]"
scene=$1 outdir=$2 n=$3
shift 3
[[ $n =~ ^[1-9][0-9]*$ ]] || die "N must be a positive whole number of tasks, not '$n'"
for opt in "$@"; do
    case $opt in
    -o | --outfile | --outfile=* | -o?* | --tile | --tile=* | --crop | --crop=* | --pixel-bounds | --pixel-bounds=*)
        die "$opt: the script chooses each task's part and output file" ;;
    esac
done
command -v sbatch >/dev/null || die "sbatch not found: is this a Slurm submit host?"

here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
whitted=${WHITTED:-$(command -v whitted || true)}
[[ -n $whitted ]] || whitted=$here/../../target/release/whitted
[[ -x $whitted ]] || die "no whitted binary at '$whitted' (set WHITTED, or cargo build --release)"
whitted=$(cd "$(dirname "$whitted")" && pwd)/$(basename "$whitted")

# a scene file by absolute path (jobs may start elsewhere); a built-in scene by name
if [[ -e $scene || $scene == *.toml ]]; then
    [[ -f $scene ]] || die "$scene: no such scene file"
    scene=$(cd "$(dirname "$scene")" && pwd)/$(basename "$scene")
fi
name=$(basename "$scene" .toml)
mkdir -p "$outdir"
outdir=$(cd "$outdir" && pwd)

# shellcheck disable=SC2086 # SBATCH_OPTS is a list of options
render_job=$(sbatch --parsable ${SBATCH_OPTS:-} --job-name="whitted-$name" \
    --array="0-$((n - 1))" --output="$outdir/slurm-%A_%a.out" \
    "$here/submit.sh" --task-render "$whitted" "$scene" "$outdir" "$name" "$n" "$@")
render_job=${render_job%%;*}
echo "render: array job $render_job ($n tasks)"
wait_opt=()
[[ $wait == 1 ]] && wait_opt=(--wait)
# shellcheck disable=SC2086
merge_job=$(sbatch --parsable ${SBATCH_OPTS:-} "${wait_opt[@]}" --job-name="whitted-$name-merge" \
    --dependency="afterok:$render_job" --kill-on-invalid-dep=yes \
    --output="$outdir/slurm-%j-merge.out" \
    "$here/submit.sh" --task-merge "$whitted" "$outdir" "$name" "$n") && status=0 || status=$?
merge_job=${merge_job%%;*}
echo "merge: job $merge_job -> $outdir/$name.exr"
if [[ $wait == 1 ]]; then
    # sbatch --wait gives the job's exit code, but 0 for a job cancelled before it ran (as
    # the merge is when a task fails): the job's final state decides
    info=$(scontrol show job "$merge_job" 2>/dev/null || true)
    state=$(sed -n 's/.*JobState=\([A-Z_]*\).*/\1/p' <<<"$info" | head -n 1)
    if [[ $state != COMPLETED ]]; then
        echo "merge: job $merge_job ended ${state:-in an unknown state}: no image (see $outdir/slurm-*.out)" >&2
        [[ $status != 0 ]] || status=1
    fi
fi
exit "$status"

#!/usr/bin/env bash
# Full-disk scan (issue 29, long; not part of any test suite): runs softevo-mpi into tmpfs
# mounts of 200k..800k (20k steps), solo and packed (--seeds 1-3), counts crashes (a signal,
# e.g. SIGSEGV inside libhdf5), clean stops (exit != 0, cause printed, archive readable) and
# runs that fit; every `SAMPLE`th stopped archive is resumed on a roomy disk and its
# fitness_digest compared with an uninterrupted run's. Needs root (mount).
#
#   tools/dev/full_disk_scan.sh BUILD_DIR [CONFIG] [SAMPLE] [MODES] [SIZES]
#
# MODES: "solo packed" (default), or one of them. SIZES: "FIRST STEP LAST" in kB (default
# "200 20 800"). Prints one line per case and a summary;
# exits 1 if anything crashed, a stop left an archive `running` or a resume differed.
set -u
build=${1:?usage: full_disk_scan.sh BUILD_DIR [CONFIG] [SAMPLE] [MODES] [SIZES]}
config=${2:-configs/quickstart.toml}
sample=${3:-3}
modes=${4:-solo packed}
sizes=${5:-200 20 800}
mpi="$build/bin/softevo-mpi"
cli="$build/bin/softevo"
if [ "$(id -u)" != 0 ]; then
  echo "full_disk_scan.sh: needs root (it mounts tmpfs file systems); skipped"
  exit 77
fi
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
work=$(mktemp -d /tmp/full-disk-scan.XXXXXX)
mnt="$work/mnt"
mkdir -p "$mnt" "$work/ref"
cleanup() {
  umount -l "$mnt" 2>/dev/null
  rm -rf "$work"
}
trap cleanup EXIT

digest() { "$cli" info "$1" 2>/dev/null | awk '$1 == "fitness_digest" {print $2}'; }
state() { "$cli" info "$1" 2>/dev/null | awk '$1 == "state" {print $2}'; }
name_of() { basename "$config" .toml; }

# Uninterrupted references (of the modes scanned).
case " $modes " in *" solo "*)
  "$mpi" -q --config "$config" --out "$work/ref/solo.h5" >/dev/null 2>&1 || {
    echo "reference run failed"
    exit 2
  }
  ;;
esac
case " $modes " in *" packed "*)
  "$mpi" -q --config "$config" --seeds 1-3 --out-dir "$work/ref" >/dev/null 2>&1 || {
    echo "packed reference run failed"
    exit 2
  }
  ;;
esac

crashes=0 stops=0 fits=0 resumed=0 resume_bad=0 unrecorded=0 n=0
for mode in $modes; do
  for size in $(seq $sizes); do
    n=$((n + 1))
    mount -t tmpfs -o "size=${size}k" tmpfs "$mnt" || exit 2
    log="$work/$mode-$size.log"
    if [ "$mode" = solo ]; then
      "$mpi" --config "$config" --out "$mnt/run.h5" >"$log" 2>&1
      rc=$?
      outs=("$mnt/run.h5")
      refs=("$work/ref/solo.h5")
    else
      "$mpi" --config "$config" --seeds 1-3 --out-dir "$mnt" >"$log" 2>&1
      rc=$?
      outs=() refs=()
      for s in 01 02 03; do
        outs+=("$mnt/$(name_of)-$s.h5")
        refs+=("$work/ref/$(name_of)-$s.h5")
      done
    fi
    if [ $rc -ge 128 ] || grep -q "Segmentation fault\|Signal: \|signal [0-9]* (" "$log"; then
      verdict=CRASH
      crashes=$((crashes + 1))
    elif [ $rc -eq 0 ]; then
      verdict=fits
      fits=$((fits + 1))
    else
      verdict=stop
      stops=$((stops + 1))
    fi
    states=""
    for o in "${outs[@]}"; do states="$states $(state "$o")"; done
    case "$states" in *running*) [ $verdict = stop ] && unrecorded=$((unrecorded + 1)) ;; esac
    extra=""
    if [ $verdict != fits ] && [ $((n % sample)) -eq 0 ]; then
      mount -o remount,size=64m "$mnt"
      if [ "$mode" = solo ]; then
        "$mpi" -q --config "$config" --out "$mnt/run.h5" --resume >>"$log" 2>&1
      else
        "$mpi" -q --config "$config" --seeds 1-3 --out-dir "$mnt" --resume >>"$log" 2>&1
      fi
      rrc=$?
      same=yes
      for i in "${!outs[@]}"; do
        [ "$(digest "${outs[$i]}")" = "$(digest "${refs[$i]}")" ] || same=no
      done
      resumed=$((resumed + 1))
      [ $rrc -eq 0 ] && [ $same = yes ] || resume_bad=$((resume_bad + 1))
      extra=" resume: exit $rrc, digests equal: $same"
    fi
    echo "$mode ${size}k: exit $rc $verdict, state:$states$extra"
    umount -l "$mnt"
  done
done
echo "cases $n: crashes $crashes, clean stops $stops (state left running: $unrecorded), fit $fits;" \
  "resumed $resumed, resume failures or digest differences $resume_bad"
[ $crashes -eq 0 ] && [ $resume_bad -eq 0 ] && [ $unrecorded -eq 0 ]

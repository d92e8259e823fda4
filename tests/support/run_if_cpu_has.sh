#!/bin/sh
# run_if_cpu_has.sh "<flags>" PROGRAM [ARGS...]: runs PROGRAM if /proc/cpuinfo lists every flag,
# else exits 77 (CTest SKIP_RETURN_CODE) saying which one is missing.
flags="$1"; shift
for f in $flags; do
  grep -qw "$f" /proc/cpuinfo || { echo "skipped: this CPU lacks '$f'"; exit 77; }
done
exec "$@"

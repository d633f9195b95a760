#!/bin/sh
# Runs G-code programs through LinuxCNC 2.9's own trajectory planner,
# headless, and prints "<seconds> <program>" for each: the time motion was
# not in position. Needs the Debian package linuxcnc-uspace.
#   crates/millplan-plan/tests/linuxcnc/run.sh OUT_FILE PROGRAM.ngc...
set -e
here=$(cd "$(dirname "$0")" && pwd)
out=$(realpath -m "$1")
shift
progs=""
for p in "$@"; do progs="$progs:$(realpath "$p")"; done
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cp "$here/sim.ini" "$here/sim.hal" "$here/sim.tbl" "$here/run.py" "$work/"
cd "$work"
# rtapi_app refuses to run as root without real-time: it runs as a
# non-root fallback user, whose FIFO must be where that user may write.
if [ "$(id -u)" = 0 ]; then
    export RTAPI_UID="${RTAPI_UID:-65534}"
    chmod 777 "$work"
    export RTAPI_FIFO_PATH="$work/rtapi_fifo"
fi
LCNC_PROGRAMS="$progs" LCNC_OUT="$out" linuxcnc sim.ini > "$work/linuxcnc.log" 2>&1 || {
    cat "$work/linuxcnc.log" >&2
    exit 1
}
cat "$out"

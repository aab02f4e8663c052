#!/bin/sh
# Runs a command under a fresh Xvfb (xvfb-run), starting the display search at N. Xvfb under a loaded
# machine sometimes refuses the first connection ("bad X server connection"), which aborts pvbatch before
# the test has checked anything: only then the command is run again, at most twice more.
# Usage: xrun.sh N COMMAND [ARG...]
n=$1; shift
log=$(mktemp)
for attempt in 1 2 3; do
  xvfb-run -a -n "$n" "$@" >"$log" 2>&1
  rc=$?
  if [ $rc -eq 0 ] || ! grep -q "bad X server connection" "$log"; then break; fi
  echo "xrun.sh: attempt $attempt: the X server refused the connection; again" >&2
done
cat "$log"
rm -f "$log"
exit $rc

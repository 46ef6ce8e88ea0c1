# Sourced by benchmark scripts: wait_quiet waits up to $QUIET_WAIT seconds (default 0) until no
# compiler, test binary or other scoopsim run is on the host, as a shared host needs before a
# timed run.
QUIET_WAIT=${QUIET_WAIT:-0}
wait_quiet() {
  local waited=0
  while [ "$waited" -lt "$QUIET_WAIT" ] &&
    pgrep -f 'cc1plus|ctest|_tests|mpirun|scoopsim (run|bed|bench|sweep|study)' >/dev/null; do
    sleep 5
    waited=$((waited + 5))
  done
}

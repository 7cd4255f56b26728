# Shared by e2e/run.sh and bench/e2e_load.sh (sourced, from e2e/).
# run <name> <env...> -- <playwright args...>: one Playwright run, its output prefixed, its status returned.
run() {
  local name=$1; shift
  local -a env=()
  while [ "$1" != "--" ]; do env+=("$1"); shift; done
  shift
  env "${env[@]}" E2E_OUTPUT_DIR="test-results/$name" npx playwright test "$@" 2>&1 | sed -u "s/^/[$name] /"
  return "${PIPESTATUS[0]}"
}

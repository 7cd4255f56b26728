#!/usr/bin/env bash
# One Playwright run of e2e/run.sh or bench/e2e_load.sh, from e2e/: bash lib/run-one.sh <name> <env...> -- <args...>
# Its output goes to test-results/<name>/, its lines prefixed with [<name>]; exits with Playwright's status.
set -uo pipefail
name=$1; shift
env=()
while [ "$1" != "--" ]; do env+=("$1"); shift; done
shift
env "${env[@]}" E2E_OUTPUT_DIR="test-results/$name" npx playwright test "$@" 2>&1 | sed -u "s/^/[$name] /"
exit "${PIPESTATUS[0]}"

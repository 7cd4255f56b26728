#!/usr/bin/env bash
# Idempotent install step shared by `npm start` and `npm test`.
# Each stage is skipped when its inputs have not changed since it last succeeded (stamps in .state/).
# Usage: bootstrap.sh [stage...]   stages: apt venv npm catkin ros2 app (default: all, in that order)
set -euo pipefail
STAGES=" ${*:-apt venv npm catkin ros2 app} "
want() { [[ "$STAGES" == *" $1 "* ]]; }
ROOT="$(cd "$(dirname "$0")/.." && pwd)"
cd "$ROOT"
STATE="$ROOT/.state"
mkdir -p "$STATE"
log() { printf '[bootstrap] %s\n' "$*" >&2; }
t0=$(date +%s)

mapfile -t APT_PACKAGES < <(sed -e 's/#.*//' -e '/^[[:space:]]*$/d' scripts/apt-packages.txt)

# Stamp = hash of the files that define a stage; the stage reruns when they change.
stamp_of() { cat "$@" 2>/dev/null | sha256sum | cut -c1-16; }
fresh() { [[ -f "$STATE/$1" && "$(cat "$STATE/$1")" == "$2" ]]; }
mark() { echo "$2" > "$STATE/$1"; }

# 1. Debian packages
missing=()
want apt || APT_PACKAGES=()
for p in "${APT_PACKAGES[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  log "installing Debian packages: ${missing[*]}"
  SUDO=""; [[ $(id -u) -ne 0 ]] && SUDO="sudo"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi

# 2. Python venv that still sees Debian's rospy
if want venv && [[ ! -x .venv/bin/python ]]; then
  log "creating .venv"
  /usr/bin/python3 -m venv --system-site-packages .venv
fi
s=$(stamp_of requirements.txt scripts/venv_first.py; grep -c ignore-installed scripts/bootstrap.sh)
if want venv && ! fresh pip "$s"; then
  log "pip install -r requirements.txt"
  # --ignore-installed: the whole dependency closure goes into the venv, even where a Debian package (e.g.
  # python3-twisted, python3-openssl on a robot PC) seems to satisfy it; mixed copies break at import.
  .venv/bin/python -m pip install -q --disable-pip-version-check --ignore-installed -r requirements.txt
  # The venv's own packages must win over Debian's (see scripts/venv_first.py).
  site=$(.venv/bin/python -c 'import sysconfig; print(sysconfig.get_paths()["purelib"])')
  cp scripts/venv_first.py "$site/_cell_venv_first.py"
  echo "import _cell_venv_first" > "$site/_cell_venv_first.pth"
  mark pip "$s"
fi

# 3. npm packages
s=$(stamp_of package-lock.json)
if want npm && { ! fresh npm "$s" || [[ ! -d node_modules ]]; }; then
  log "npm ci"
  PLAYWRIGHT_SKIP_BROWSER_DOWNLOAD=1 npm ci --no-audit --no-fund --loglevel=error
  mark npm "$s"
fi

# 4. catkin workspace (msg/srv/action generation, python paths)
s=$( (find ros_backend/src -type f \( -name '*.msg' -o -name '*.srv' -o -name '*.action' -o -name CMakeLists.txt -o -name package.xml -o -name setup.py \) | sort | xargs cat) | sha256sum | cut -c1-16)
if want catkin && { ! fresh catkin "$s" || [[ ! -f ros_backend/devel/setup.bash ]]; }; then
  log "catkin_make"
  (cd ros_backend && ROS_LANG_DISABLE=gencpp:genlisp:geneus:gennodejs \
    catkin_make -DPYTHON_EXECUTABLE=/usr/bin/python3 -DCATKIN_ENABLE_TESTING=OFF >"$STATE/catkin.log" 2>&1) \
    || { tail -40 "$STATE/catkin.log" >&2; exit 1; }
  mark catkin "$s"
fi

# 5. ROS 2 Jazzy: a venv of its own (rosidl and genpy make Python packages of the same names) and our interfaces
# built for it from the same definitions (ros_backend/ros2/build_interfaces.py); each step reruns only on its inputs
s=$(stamp_of requirements-ros2.txt)
if want ros2 && { ! fresh ros2-pip "$s" || [[ ! -x .venv-ros2/bin/python ]]; }; then
  log "ROS 2 Jazzy venv"
  [[ -x .venv-ros2/bin/python ]] || /usr/bin/python3 -m venv .venv-ros2
  .venv-ros2/bin/python -m pip install -q --disable-pip-version-check -r requirements-ros2.txt >"$STATE/ros2.log" 2>&1 \
    || { tail -40 "$STATE/ros2.log" >&2; exit 1; }
  mark ros2-pip "$s"
fi
s=$( (cat requirements-ros2.txt; find ros_backend/ros2/build_interfaces.py ros_backend/ros2/interfaces ros_backend/src/cell_msgs -type f | sort | xargs cat) | sha256sum | cut -c1-16)
if want ros2 && { ! fresh ros2 "$s" || [[ ! -d ros_backend/install-ros2/share/cell_msgs ]]; }; then
  log "ROS 2 interfaces"
  .venv-ros2/bin/python ros_backend/ros2/build_interfaces.py --venv .venv-ros2 --prefix ros_backend/install-ros2 \
    --build "$STATE/ros2-build" >"$STATE/ros2-build.log" 2>&1 || { tail -40 "$STATE/ros2-build.log" >&2; exit 1; }
  mark ros2 "$s"
fi

# 6. the PWA build
s=$( (find app/src app/static app/messages app/project.inlang -type f -not -path 'app/src/lib/paraglide/*' 2>/dev/null | sort | xargs cat; cat app/package.json app/vite.config.* app/svelte.config.* app/i18n.*.js app/preload-fallback.js 2>/dev/null) | sha256sum | cut -c1-16)
if want app && { ! fresh app "$s" || [[ ! -f app/build/index.html ]]; }; then
  log "building app"
  npm run build -w app --silent >"$STATE/app-build.log" 2>&1 || { tail -40 "$STATE/app-build.log" >&2; exit 1; }
  mark app "$s"
fi

if want app; then log "ready in $(( $(date +%s) - t0 )) s"; fi

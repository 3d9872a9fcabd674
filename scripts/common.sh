# Shared by the scripts in scripts/ (sourced, not run): package installation and the checks the
# linters need. Each function takes the calling script's name for its messages.

# install_missing_packages NAME PACKAGE...: apt-installs the Debian packages that are not installed,
# and nothing when all are (idempotent). Needs root or sudo.
install_missing_packages() {
  local name=$1
  shift
  local missing=() p
  for p in "$@"; do
    if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
      missing+=("$p")
    fi
  done
  if [ ${#missing[@]} -eq 0 ]; then
    echo "$name: all $# packages present, nothing to do"
    return 0
  fi
  echo "$name: installing ${missing[*]}"
  local sudo=""
  if [ "$(id -u)" -ne 0 ]; then sudo="sudo"; fi
  $sudo env DEBIAN_FRONTEND=noninteractive apt-get update -qq
  $sudo env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends "${missing[@]}"
}

# require_tool NAME COMMAND PACKAGE: installs PACKAGE when COMMAND is not on the PATH.
require_tool() {
  if ! command -v "$2" > /dev/null 2>&1; then
    install_missing_packages "$1" "$3"
  fi
}

# require_compile_commands NAME BUILD_DIR: fails unless BUILD_DIR has been configured.
require_compile_commands() {
  if [ ! -f "$2/compile_commands.json" ]; then
    echo "$1: $2/compile_commands.json is missing: configure that build first" >&2
    exit 1
  fi
}

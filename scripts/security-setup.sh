#!/usr/bin/env bash
# The independent secure DDS peer of issue 19: Debian's Cyclone DDS 0.10 (libddsc0debian ships
# the three DDS Security plugins: auth, access control, crypto) and the Cyclone DDS Python
# binding built against it (PyPI's cyclonedds wheel bundles a library without security) in
# .venv-sec; and OpenSSL's development files for rustdds' DDS Security. Installs with apt-get when missing (root, as in CI); skips what is done.
#   usage: scripts/security-setup.sh
set -euo pipefail
cd "$(dirname "$0")/.."
# rustdds' DDS Security (fcc_ros' default `security` feature) links OpenSSL: its headers and
# pkg-config for the openssl-sys build.
if ! pkg-config --exists openssl 2>/dev/null; then
  if [ "$(id -u)" -ne 0 ]; then
    echo "security-setup: needs libssl-dev and pkg-config (apt-get install as root)" >&2
    exit 1
  fi
  DEBIAN_FRONTEND=noninteractive apt-get install -o DPkg::Lock::Timeout=600 -y -q libssl-dev pkg-config > /dev/null
fi
plugins=/usr/lib/x86_64-linux-gnu/libddsc0debian
if [ ! -e "$plugins/libdds_security_auth.so" ] || [ ! -e /usr/include/dds/dds.h ]; then
  if [ "$(id -u)" -ne 0 ]; then
    echo "security-setup: needs libddsc0debian and cyclonedds-dev (apt-get install as root)" >&2
    exit 1
  fi
  DEBIAN_FRONTEND=noninteractive apt-get install -o DPkg::Lock::Timeout=600 -y -q libddsc0debian cyclonedds-dev > /dev/null
fi
# The binding's build looks for CYCLONEDDS_HOME/{include,bin,lib/libddsc.so}: a directory of
# links to Debian's files.
home="$PWD/target/cyclonedds-home"
mkdir -p "$home/lib"
ln -sfn /usr/include "$home/include"
ln -sfn /usr/bin "$home/bin"
ln -sf /usr/lib/x86_64-linux-gnu/libddsc.so "$home/lib/libddsc.so"
for f in "$plugins"/*.so; do ln -sf "$f" "$home/lib/"; done
# The binding records the library's path at build time: it must be this checkout's (pip's wheel
# cache would hand out one built for another checkout, hence --no-cache-dir).
if ! .venv-sec/bin/python -c 'import cyclonedds.__library__ as l, sys; sys.exit(l.library_path != sys.argv[1])' "$home/lib/libddsc.so" 2>/dev/null; then
  rm -rf .venv-sec
  python3 -m venv .venv-sec
  CYCLONEDDS_HOME="$home" .venv-sec/bin/pip install -q --disable-pip-version-check --no-cache-dir \
    --no-binary cyclonedds cyclonedds==0.10.2
fi
echo "security-setup: .venv-sec (cyclonedds $(.venv-sec/bin/python -c 'import cyclonedds.__library__ as l; print(l.library_path)'))"

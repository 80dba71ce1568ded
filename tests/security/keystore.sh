#!/usr/bin/env bash
# SROS2 keystore (issue 19), in ONE loopback-only network namespace: `fcc-keystore create`
# makes a keystore; openssl checks its certificates and signatures; Debian's Cyclone DDS 0.10
# with its security plugins (tests/security/keystore_peer.py, .venv-sec from
# scripts/security-setup.sh) authenticates with the bridge, ground-station and observer
# enclaves: commands pass from the ground station, the observer's are refused, an
# unauthenticated participant sees nothing. Bad use of fcc-keystore gets one clear line.
#   usage: tests/security/keystore.sh   (~15 s)
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
root="$(cd "$here/../.." && pwd)"
. "$root/tests/lib/loopback_only.sh"
loopback_only "$0"
. "$root/tests/lib/scratch.sh"
py="$root/.venv-sec/bin/python"
ks="$tmp/keystore"
rc=0
check() { # NAME CONDITION-EXIT-STATUS DETAIL
  if [ "$2" -eq 0 ]; then echo "PASS $1${3:+: $3}"; else echo "FAIL $1${3:+: $3}"; rc=1; fi
}
"$bin/fcc-keystore" create "$ks"
ca="$ks/public/ca.cert.pem"
for d in "$ks"/enclaves/fcc/fcc_bridge "$ks"/enclaves/fcc/fcc_mission "$ks"/enclaves/ground_station "$ks"/enclaves/observer; do
  n=${d#"$ks"/enclaves}
  set +e
  subj=$(openssl x509 -in "$d/cert.pem" -noout -subject -nameopt RFC2253); a=$?
  subj=${subj#subject=}
  openssl verify -CAfile "$ca" "$d/cert.pem" > /dev/null 2>&1; b=$?
  openssl smime -verify -in "$d/permissions.p7s" -CAfile "$ca" -out /dev/null 2>/dev/null; c=$?
  openssl smime -verify -in "$d/governance.p7s" -CAfile "$ca" -out /dev/null 2>/dev/null; e=$?
  set -e
  [ "$subj" = "CN=$n" ]; f=$?
  check "enclave $n: certificate from the CA with subject CN=$n; permissions and governance signed by it" \
    $((a + b + c + e + f)) "subject $subj"
done
set +e
out=$("$bin/fcc-keystore" create "$ks" 2>&1); s=$?
check "create over an existing keystore is refused" $(( s == 1 ? 0 : 1 )) "$out"
out=$("$bin/fcc-keystore" enclave "$ks" /a/../b --role ground 2>&1); s=$?
check "a bad enclave name is refused" $(( s == 1 ? 0 : 1 )) "$out"
out=$("$bin/fcc-keystore" enclave "$ks" /gs2 --role admin 2>&1); s=$?
check "an unknown role is refused (exit 2)" $(( s == 2 ? 0 : 1 )) "$out"
"$py" "$here/keystore_peer.py" "$ks" --seconds "${FCC_SECURITY_SECONDS:-6}"; s=$?
check "Cyclone DDS 0.10 with its security plugins honours the keystore" $s
set -e
exit $rc

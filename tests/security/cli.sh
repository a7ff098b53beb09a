#!/bin/sh
# The command-line path of a secured classroom: palp-server --pki and palp-client
# --pki/--identity (the identity's name becomes the trainee name), a wrong --name
# refused by the server, a bad identity refused before any network use, a station without an
# identity told that the classroom may be secured (not only "is the server running?"), a plain
# server refused a DDS config beyond loopback unless --insecure, an identity whose key is not its
# certificate's or whose certificate another CA issued refused up front, and a secured
# trainee whose process is stopped 1.5 s going on in its session (the server holds it;
# the station, authenticated again, asks with the same request). Domain 131.
# A palp-recorder without an identity says, 10 s in, that the classroom may be secured.
# Permissions the PKI script wrote damaged (until 2026-12-06) are mended by its init, and an
# instructor's observer, recorder and palp-web on them say so and what to do.
# Bob, authenticated, writes contacts and marks naming alice's session into his own partition (his
# permissions allow it): the secured recorder and palp-web take none of them for hers (session 73).
# usage: cli.sh palp-server palp-client PKI_DIR PALP_RECORDER PALP_WEB FORGER
set -u
. "$(dirname "$0")/../stall.sh"
server=$1 client=$2 pki=$3 recorder=$4 web=$5 forger=$6
out=$(mktemp -d)
fail=0
check() { if eval "$2"; then echo "ok   $1"; else echo "FAIL $1"; fail=1; fi; }
# resign DIR STEM: DIR/STEM.xml, edited by the test, signed again by DIR's CA into DIR/STEM.p7s
resign() { openssl smime -sign -in "$1/$2.xml" -text -out "$1/$2.p7s" -signer "$1/ca.cert.pem" -inkey "$1/ca/ca.key.pem"; }
# --duration: the server outlives every station below (~25 s of them on a quiet machine; 30 s ended the
# stall check's session mid-way in a fresh clone's run once the permissions checks came before it, 2026-12-05);
# it is stopped by SIGINT at the end anyway
"$server" --domain 131 --no-db --pki "$pki" --duration 90 >"$out/server.log" 2>&1 &
spid=$!
"$recorder" --domain 131 --db "$out/rec.db" --duration 11.5 >"$out/recorder.log" 2>&1 &
rpid=$!
sleep 1
"$client" --role trainee --domain 131 --phantom 1 --pki "$pki" --identity trainee/alice --duration 2 --quiet \
  >"$out/alice.log" 2>&1
check "a secured trainee runs a session (exit $?)" "grep -q 'session [0-9]*: .* contact samples sent' '$out/alice.log'"
"$client" --role trainee --domain 131 --phantom 1 --pki "$pki" --identity trainee/bob --name alice --duration 1 \
  --timeout 4 --quiet >"$out/bob.log" 2>&1
rc=$?
check "bob calling himself alice is refused (exit $rc)" "[ $rc -ne 0 ] && grep -q 'not the authenticated identity trainee/bob' '$out/bob.log'"
"$client" --role trainee --domain 131 --phantom 1 --pki "$pki" --identity trainee/Bob --duration 1 >"$out/bad.log" 2>&1
rc=$?
check "a malformed identity is refused up front (exit $rc)" "[ $rc -eq 1 ] && grep -q 'identity \"trainee/Bob\"' '$out/bad.log'"
"$client" --role trainee --domain 131 --phantom 1 --pki "$pki" --duration 1 >"$out/half.log" 2>&1
rc=$?
check "--pki without --identity is refused (exit $rc)" "[ $rc -eq 1 ] && grep -q 'go together' '$out/half.log'"
# A recorder started with a trainee's identity is refused up front, saying which identity it needs (it
# failed at its readers with "re-issue them with ... init", which mends nothing: bob's are sound).
"$recorder" --domain 131 --db "$out/bob-rec.db" --pki "$pki" --identity trainee/bob --duration 1 >"$out/bob-rec.log" 2>&1
rc=$?
check "a recorder with a trainee identity is refused up front: it needs an instructor's (exit $rc)" \
  "[ $rc -eq 2 ] && grep -q 'the recorder needs an instructor identity (instructor/NAME), not trainee/bob' '$out/bob-rec.log' && ! grep -q 're-issue' '$out/bob-rec.log' && [ ! -e '$out/bob-rec.db' ]"
# dave was revoked (make_pki.sh): his files moved to DIR/revoked; the classroom's copy says so
# rather than "cannot read" (idl/palp_dds_security.c), before any network use.
"$client" --pki "$pki" --identity trainee/dave --role trainee --phantom 1 --duration 1 >"$out/dave.log" 2>&1; rc=$?
check "a revoked identity is told it was revoked, and how to get a new one (exit $rc)" \
  "[ $rc -eq 1 ] && grep -q 'identity trainee/dave was revoked in this classroom (its files were moved to .*/revoked/trainee_dave-[0-9T]*\\.\\*): ask the instructor for a new one (make-classroom-pki.sh DIR add trainee dave)' '$out/dave.log'"
# Another identity's revoked files are not this one's (session 90's review): trainee/zed, never issued, beside
# a revoked trainee/zed-x, is not told it was revoked (before: "trainee/zed was revoked", pointed at zed-x's).
touch "$pki/revoked/trainee_zed-x-20261201T101010.cert.pem"
"$client" --pki "$pki" --identity trainee/zed --role trainee --phantom 1 --duration 1 >"$out/zed.log" 2>&1; rc=$?
rm -f "$pki/revoked/trainee_zed-x-20261201T101010.cert.pem"
check "an identity never issued is not told another's revocation (exit $rc): $(head -c 160 "$out/zed.log")" \
  "[ $rc -eq 1 ] && ! grep -q 'was revoked' '$out/zed.log' && grep -q 'trainee/zed' '$out/zed.log'"
# The --check runs below that assert a refusal (or its absence) for DDS Security or the DDS config run on
# check-server.json, one dome: no phantom takes part in what they assert, and config/server.json's five
# domes cost each run ~0.25 s of CPU building their models (one: ~0.05 s; 2026-12-07). The lines
# default-palp.example gives keep their own config.
check_server() { "$server" --config "$(dirname "$0")/check-server.json" "$@"; }
# A DDS config that may reach a network (the lab example): refused unsecured, before any participant
# exists (--check stops there too), accepted with --insecure or --pki. Nothing here creates one.
lab=$(dirname "$0")/../../config/cyclonedds-lab.xml.example
check_server --dds-config "$lab" --check >"$out/lab.log" 2>&1
rc=$?
check "a plain server with a DDS config beyond loopback is refused (exit $rc)" \
  "[ $rc -eq 2 ] && grep -q 'refusing to serve beyond loopback without DDS Security' '$out/lab.log' && grep -q 'PALP_DDS_INTERFACE' '$out/lab.log'"
check_server --dds-config "$lab" --check --insecure >"$out/lab2.log" 2>&1 && check_server --dds-config "$lab" --check --pki "$pki" >>"$out/lab2.log" 2>&1
rc=$?
check "the same with --insecure, or secured with --pki, passes its check (exit $rc)" "[ $rc -eq 0 ]"
# Session 81 review (operations): config/default-palp.example's lab lines, as an administrator copies them
# (/etc/palp = the installed config/ with cyclonedds-lab.xml from its example, /etc/palp/certs = this PKI):
# its PALP_SERVER_ARGS had no --pki, so the server refused the lab DDS config (exit 2) and its unit
# restarted it every 2 s. The server's line now passes --check; the recorder's and palp-web's name the PKI
# and an instructor identity (each of them refuses a PKI without one). --check makes no participant.
example=$(dirname "$0")/../../config/default-palp.example
etc=$out/etc/palp
mkdir -p "$out/etc" && cp -rL "$(dirname "$0")/../../config" "$etc" && cp "$etc/cyclonedds-lab.xml.example" "$etc/cyclonedds-lab.xml" \
  && ln -s "$(cd "$pki" && pwd)" "$etc/certs"
example_args() { sed -n "s|^#*$1=\"\(.*\)\"\$|\1|p" "$example" | sed "s|/etc/palp|$etc|g"; }
sargs=$(example_args PALP_SERVER_ARGS)
# shellcheck disable=SC2086 # split as systemd splits $PALP_SERVER_ARGS
"$server" $sargs --check >"$out/example.log" 2>&1
rc=$?
check "default-palp.example's PALP_SERVER_ARGS pass palp-server --check with the lab DDS config (exit $rc: $(head -c 200 "$out/example.log"))" \
  "[ $rc -eq 0 ] && grep -q 'DDS Security identity readable' '$out/example.log' && printf '%s\\n' '$sargs' | grep -qF -- '--dds-config $etc/cyclonedds-lab.xml'"
"$server" $(printf '%s\n' "$sargs" | sed 's|--pki [^ ]*||') --check >"$out/example-nopki.log" 2>&1
rc=$?
check "the same line without its --pki is refused (exit $rc: the lab config reaches beyond loopback)" \
  "[ $rc -eq 2 ] && grep -q 'refusing to serve beyond loopback' '$out/example-nopki.log'"
for v in PALP_RECORDER_ARGS PALP_WEB_ARGS; do
  a=$(example_args $v)
  id=$(printf '%s\n' "$a" | sed -n 's|.*--identity \(instructor/[a-z0-9_-]*\).*|\1|p')
  check "default-palp.example's $v: --pki $etc/certs and an instructor identity (${id:-none})" \
    "printf '%s\\n' '$a' | grep -qF -- '--pki $etc/certs' && [ -n '$id' ] && printf '%s\\n' '$a' | grep -qF -- '--dds-config $etc/cyclonedds-lab.xml'"
done

# Session 81 review: --check refuses what the start refuses for DDS Security (it passed a trainee's
# identity, an empty one, which with a PKI served the classroom unsecured, and domain 231), and a
# start so refused makes no session log (it made the file, schema and all, before refusing).
for case in "--identity trainee/alice|is not the server's" "--identity ''|identity: empty: with a PKI directory" \
            "--domain 231|domain 231: a classroom's governance covers domains 0-230"; do
  opt=${case%%|*} want=${case#*|}
  eval "check_server --pki \"\$pki\" $opt --check" >"$out/chk.log" 2>&1
  rc=$?
  check "--check $opt refused (exit $rc): $want" "[ $rc -ne 0 ] && grep -qF \"$want\" '$out/chk.log'"
done
printf '{"domain_id": 131, "database": "%s/newdir/s.db", "phantoms": [{"id": 1, "name": "a", "scene": "%s"}]}\n' \
  "$out" "$(cd "$(dirname "$0")/../../config" && pwd)/paper_step.json" > "$out/db-server.json"
"$server" --config "$out/db-server.json" --pki "$pki" --identity trainee/alice --duration 1 >"$out/dbstart.log" 2>&1
rc=$?
check "a start refused for its identity makes no session log (exit $rc)" \
  "[ $rc -ne 0 ] && grep -qF \"is not the server's\" '$out/dbstart.log' && [ ! -e '$out/newdir/s.db' ]"
# (6 s: the server names a plain participant that shows no endpoint 3 s after it first saw it)
"$client" --role trainee --domain 131 --phantom 1 --name zed --duration 1 --timeout 6 >"$out/plain.log" 2>&1
rc=$?
check "a station without an identity is told the classroom may be secured (exit $rc)" \
  "[ $rc -ne 0 ] && grep -q 'none of which answered: if the classroom runs with DDS Security, give --pki DIR --identity' '$out/plain.log'"
# A private key every user of the machine can read is refused before any network use.
cp -r "$pki" "$out/openkey"
chmod 644 "$out/openkey/trainee/alice.key.pem"
"$client" --role trainee --domain 131 --phantom 1 --pki "$out/openkey" --identity trainee/alice --duration 1 \
  >"$out/openkey.log" 2>&1
rc=$?
check "a world-readable private key is refused (exit $rc)" \
  "[ $rc -eq 1 ] && grep -q 'alice.key.pem is readable by every user of this machine (mode 0644): chmod o-rwx' '$out/openkey.log'"
# A key that is not its certificate's, and a certificate another CA issued: each fails every handshake
# with nothing said at creation (the station heard only "no answer"); both refused up front, named.
cp -r "$pki" "$out/swapped"
cp "$out/swapped/trainee/bob.key.pem" "$out/swapped/trainee/alice.key.pem"
"$client" --role trainee --domain 131 --phantom 1 --pki "$out/swapped" --identity trainee/alice --duration 1 \
  >"$out/swapped.log" 2>&1
rc=$?
check "bob's key beside alice's certificate is refused before any network use (exit $rc)" \
  "[ $rc -eq 1 ] && grep -q 'alice.key.pem is not the key of its certificate' '$out/swapped.log'"
cp "$pki/trainee/alice.key.pem" "$out/swapped/trainee/alice.key.pem"
openssl pkey -in "$pki/trainee/alice.key.pem" -aes128 -passout pass:lab -out "$out/swapped/trainee/alice.key.pem" 2>/dev/null
"$client" --role trainee --domain 131 --phantom 1 --pki "$out/swapped" --identity trainee/alice --duration 1 \
  >"$out/passphrase.log" 2>&1 </dev/null
rc=$?
check "a key with a passphrase is refused as such, not prompted for (exit $rc)" \
  "[ $rc -eq 1 ] && grep -q 'or has a passphrase (palp gives none)' '$out/passphrase.log'"
# (alice of the fixture's other CA, PKI_DIR-rogue: make_pki.sh)
cp -r "$pki" "$out/foreign"
cp "$pki-rogue/trainee/alice.cert.pem" "$pki-rogue/trainee/alice.key.pem" "$out/foreign/trainee/"
"$client" --role trainee --domain 131 --phantom 1 --pki "$out/foreign" --identity trainee/alice --duration 1 \
  >"$out/foreign.log" 2>&1
rc=$?
check "a certificate of another classroom's CA is refused before any network use (exit $rc)" \
  "[ $rc -eq 1 ] && grep -q \"was not issued by this classroom's CA\" '$out/foreign.log'"
# The rule's edge, seen by the server's --check: group-readable (a service's group, docs/deploy.md) passes.
chmod 640 "$out/openkey/server/server.key.pem"
check_server --check --pki "$out/openkey" >"$out/check640.log" 2>&1
rc640=$?
chmod 644 "$out/openkey/server/server.key.pem"
check_server --check --pki "$out/openkey" >"$out/check644.log" 2>&1
rc=$?
check "palp-server --check: a key of mode 0640 passes (exit $rc640), 0644 is refused (exit $rc)" \
  "[ $rc640 -eq 0 ] && grep -q 'DDS Security identity readable' '$out/check640.log' && [ $rc -eq 1 ] && grep -q 'server.key.pem is readable by every user' '$out/check644.log'"
# Revocation needs the classroom CRL (session 81): a copy of the PKI without crl.pem made palp-server
# admit the revoked trainee/dave (no CRL property, revocation off) and its --check say ok. Refused now,
# for every role, naming the file and what it protects; a crl.pem that is no CRL (garbage, or the CA's
# certificate copied in its place) likewise.
cp -r "$pki" "$out/nocrl"
rm "$out/nocrl/crl.pem"
check_server --check --pki "$out/nocrl" >"$out/nocrl-check.log" 2>&1
rc=$?
check "palp-server --check refuses a PKI without crl.pem, naming it (exit $rc)" \
  "[ $rc -ne 0 ] && grep -q 'classroom CRL .*/nocrl/crl.pem: missing: without it revoked identities would be admitted' '$out/nocrl-check.log' && ! grep -q ': ok (' '$out/nocrl-check.log'"
"$client" --role trainee --domain 131 --phantom 1 --pki "$out/nocrl" --identity trainee/alice --duration 1 \
  >"$out/nocrl-client.log" 2>&1
rc=$?
check "a station without crl.pem is refused before any network use (exit $rc)" \
  "[ $rc -eq 1 ] && grep -q 'nocrl/crl.pem: missing: without it revoked identities would be admitted' '$out/nocrl-client.log'"
cp -r "$pki" "$out/badcrl"
printf 'not a CRL\n' >"$out/badcrl/crl.pem"
check_server --check --pki "$out/badcrl" >"$out/badcrl-check.log" 2>&1
rc=$?
cp "$pki/ca.cert.pem" "$out/badcrl/crl.pem"
check_server --check --pki "$out/badcrl" >"$out/cacrl-check.log" 2>&1
rc2=$?
check "palp-server --check refuses a crl.pem that is not a CRL: text (exit $rc), the CA certificate (exit $rc2)" \
  "[ $rc -ne 0 ] && [ $rc2 -ne 0 ] && grep -q 'classroom CRL .*/badcrl/crl.pem: not a PEM CRL: without it revoked identities would be admitted' '$out/badcrl-check.log' && grep -q 'badcrl/crl.pem: not a PEM CRL' '$out/cacrl-check.log'"
# Expiry ahead (2026-12-04): an identity issued for 5 days and a CRL re-issued for 3 (same CA) are
# warned of at start, 30 days ahead: an expired CRL fails every handshake.
cp -r "$pki" "$out/soon"
bash "$(dirname "$0")/../../scripts/make-classroom-pki.sh" "$out/soon" add trainee shorty --days 5 >/dev/null
(cd "$out/soon" && openssl ca -config ca/ca.cnf -gencrl -crldays 3 -out crl.pem 2>/dev/null)
check_server --check --pki "$out/soon" >"$out/soon-check.log" 2>&1
rc=$?
"$client" --role trainee --domain 131 --phantom 1 --pki "$out/soon" --identity trainee/shorty --duration 1 --timeout 4 \
  --quiet >"$out/soon-client.log" 2>&1
check "a certificate and a CRL about to expire are warned of (server --check exit $rc)" \
  "[ $rc -eq 0 ] && grep -q 'warning: DDS Security: the classroom CRL (crl.pem) expires in [23]\.[0-9] day(s)' '$out/soon-check.log' && grep -q 'WARN .*the certificate of trainee/shorty expires in [45]\.[0-9] day(s)' '$out/soon-client.log'"
# A station still on the governance before 2026-12-04 (no submessage protection anywhere, signed by the
# same CA): the server's request reader and its writer protect the topic differently and never match.
cp -r "$pki" "$out/oldgov"
sed -i 's|<metadata_protection_kind>SIGN</metadata_protection_kind>|<metadata_protection_kind>NONE</metadata_protection_kind>|' \
  "$out/oldgov/governance.xml"
resign "$out/oldgov" governance
"$client" --role trainee --domain 131 --phantom 1 --pki "$out/oldgov" --identity trainee/alice --duration 1 --timeout 4 \
  >"$out/oldgov.log" 2>&1
rc=$?
# ... whole: the hint is ~480 characters, and a 320-byte buffer cut it mid-sentence until 2026-12-05
check "a station on an old governance is not answered and is told, in full, to check it (exit $rc)" \
  "[ $rc -ne 0 ] && grep -q 'none of which answered trainee/alice: .*governance.p7s differs from this station.*is this certificate valid and not revoked? (the server.s log names each identity it refuses, and why)\$' '$out/oldgov.log'"
# Permissions edited by hand to deny bob the catalogue (a deny rule before his allow rule, signed by
# the classroom's CA): they name the topic, so his station is told they name it but not for this use,
# and how to mend them (the hint's other branch; "have no rule for" is the ivy check's below).
cp -r "$pki" "$out/denied"
python3 - "$out/denied/trainee/bob.permissions.xml" <<'PY'
import sys
p = sys.argv[1]
s = open(p).read()
deny = ("      <deny_rule>\n        <domains><id_range><min>0</min><max>230</max></id_range></domains>\n"
        "        <subscribe><topics><topic>palp_catalogue</topic></topics></subscribe>\n      </deny_rule>\n")
open(p, "w").write(s.replace("      <allow_rule>", deny + "      <allow_rule>", 1))
PY
resign "$out/denied" trainee/bob.permissions
"$client" --role trainee --domain 131 --phantom 1 --pki "$out/denied" --identity trainee/bob --duration 1 --timeout 3 \
  >"$out/denied.log" 2>&1
rc=$?
check "permissions that deny a topic they name: the station says they name it, but not for this use, and how to mend them (exit $rc)" \
  "[ $rc -ne 0 ] && grep -q 'deny_rule' '$out/denied/trainee/bob.permissions.xml' && grep -q 'cannot create topic palp_catalogue; DDS Security: the permissions of trainee/bob (.*/denied/trainee/bob.permissions.p7s) name topic palp_catalogue, but not for this use (publish or subscribe, partition), or they are not signed by this classroom.s CA: re-issue them with scripts/make-classroom-pki.sh .*/denied init' '$out/denied.log'"
# A classroom made before palp_debrief (2026-12-05): alice's permissions of version 1 have no rule
# for it. Her station still palpates (it cannot create the topic, and says so only at an exercise's
# end), and the script's init re-issues her permissions, signed, with the rule.
cp -r "$pki" "$out/oldperm"
sed -i -e '/palp permissions, version/d' -e '/<topic>palp_debrief<\/topic>/d; /<topic>palp_debrief_score<\/topic>/d' \
  -e '/<topic>palp_session_log<\/topic>/d; /<topic>palp_finger_sample<\/topic>/d' "$out/oldperm/trainee/alice.permissions.xml"
resign "$out/oldperm" trainee/alice.permissions
"$client" --role trainee --domain 131 --phantom 1 --pki "$out/oldperm" --identity trainee/alice --duration 1 \
  --timeout 4 --quiet >"$out/oldperm.log" 2>&1
rc=$?
# ... and says at its start that its permissions are older than this palp's, and what to do (since
# 2026-12-06; the version palp checks against is the script's: the two must agree)
pv=$(sed -n 's/^PERMISSIONS_VERSION=\([0-9]*\)$/\1/p' "$(dirname "$0")/../../scripts/make-classroom-pki.sh")
check "  it is told at start that its permissions (version 1) are older than this palp's $pv, and how to re-issue them" \
  "[ -n '$pv' ] && grep -q 'WARN  palp-client: DDS Security: the permissions of trainee/alice are version 1, older than this palp.s $pv: the topics added since are refused to it (they go without them, and say what is lost); re-issue them with scripts/make-classroom-pki.sh .*/oldperm init and copy .*/oldperm/trainee/alice.permissions.p7s to this machine' '$out/oldperm.log'"
check "a station whose permissions predate palp_debrief still runs its session (exit $rc)" \
  "[ $rc -eq 0 ] && ! grep -q palp_debrief '$out/oldperm/trainee/alice.permissions.xml' && grep -q 'session [0-9]*: .* contact samples sent' '$out/oldperm.log'"
# ... and a server on such permissions serves on, without debriefs, and says so (domain 132, 2 s)
sed -i -e '/palp permissions, version/d' -e '/<topic>palp_debrief<\/topic>/d; /<topic>palp_debrief_score<\/topic>/d' \
  -e '/<topic>palp_session_exercise<\/topic>/d; /<topic>palp_session_log<\/topic>/d; /<topic>palp_session_closed<\/topic>/d' \
  -e '/<topic>palp_finger_sample<\/topic>/d' "$out/oldperm/server/server.permissions.xml"
resign "$out/oldperm" server/server.permissions
# It hosts the shipped exercise "easy" (server-easy.json: phantom 11, as config/server-exercises.json has
# it, without the seven phantoms nothing here uses) and logs: alice (her permissions old too) takes "easy" by position
# and leaves; nobody can write her debrief, her station says why, and the session log records that
# none was sent, and why, so that her next attempt is not taken for one after a debrief (session 59).
"$server" --domain 132 --config "$(dirname "$0")/server-easy.json" --database "$out/oldperm.db" \
  --pki "$out/oldperm" --duration 30 >"$out/oldperm-server.log" 2>&1 &
opid=$!
sleep 1
"$client" --role trainee --domain 132 --phantom 11 --pki "$out/oldperm" --identity trainee/alice --duration 2 \
  --timeout 8 --print-period 0 --input sim:press,depth_mm=4,hold_s=1 >"$out/oldperm-ex.log" 2>&1
kill -INT $opid 2>/dev/null
wait $opid
rc=$?
check "a server whose permissions predate palp_debrief serves, and warns that it cannot debrief (exit $rc)" \
  "[ $rc -eq 0 ] && grep -q 'no debriefs: the server.s permissions do not allow topic palp_debrief' '$out/oldperm-server.log'"
check_server --pki "$out/oldperm" --check >"$out/oldperm-check.log" 2>&1
check "  ... and says at start that its permissions are older than this palp's, --check too" \
  "grep -q 'WARN  palp-server: DDS Security: the permissions of server/server are version 1, older than this palp.s $pv' '$out/oldperm-server.log' && grep -q '^palp-server: warning: DDS Security: the permissions of server/server are version 1, older than this palp.s $pv' '$out/oldperm-check.log'"
check "  ... nor send its exercises to recorders, and says that their lesions stay on it" \
  "grep -q 'no exercises for recorders: the server.s permissions do not allow topic palp_session_exercise' '$out/oldperm-server.log' && grep -q 'lesions stay on this server (the permissions predate palp_session_exercise)' '$out/oldperm-server.log'"
check "  ... nor tell the trainees of practice exercises their scores (session 64), and says so" \
  "grep -q 'no scores told to the trainees of practice exercises: the server.s permissions do not allow topic palp_debrief_score' '$out/oldperm-server.log'"
check "  ... nor name the ended sessions of a dashboard begun after them (session 69), and says so" \
  "grep -q 'no names for the ended sessions of a dashboard begun after them: the server.s permissions do not allow topic palp_session_closed' '$out/oldperm-server.log'"
check "  ... nor tell each session its own records the log lost (session 69), and says so" \
  "grep -q 'no session told its own records the session log lost (stations count the server.s instead): the server.s permissions do not allow topic palp_session_log' '$out/oldperm-server.log'"
check "  ... nor send the stations the touched triangles (session 71), and says that their coverage is approximated" \
  "grep -q 'no touched triangles for the stations. and pages. coverage (they approximate it from the local models): the server.s permissions do not allow topic palp_finger_sample' '$out/oldperm-server.log'"
check "  alice's station, on old permissions too, says at her exercise's end why she had no debrief" \
  "grep -q 'no debrief: this identity.s permissions predate it' '$out/oldperm-ex.log'"
logged=$(python3 -c "import sqlite3, sys; print('|'.join(r[0] for r in sqlite3.connect(sys.argv[1]).execute(\"select e.detail from event e join session s on s.id = e.session_id where s.trainee = 'alice' and e.kind = 'debrief'\")))" "$out/oldperm.db" 2>&1)
want="not sent (level lesions): the server's permissions do not allow topic palp_debrief (make-classroom-pki.sh re-issues them)"
same=0; [ "$logged" = "$want" ] && same=1
check "  the session log records that no debrief was sent, and why: $logged" "[ $same = 1 ]"
# Two instructors' permissions re-issued too, init run from a directory holding files (as a teacher runs
# it): ines's older by version, ivy's at this version but as the script wrote them until 2026-12-06, the
# files' names in place of "*" (its stations could then create no topic: the demo's palp-web, observer
# and recorder after the version-7 upgrade). Both come back as a fresh issue has them, "*" whole.
pkiscript=$(cd "$(dirname "$0")/../../scripts" && pwd)/make-classroom-pki.sh
cp "$out/oldperm/instructor/ines.permissions.xml" "$out/ines.intact.xml"
sed -i 's/palp permissions, version [0-9]* /palp permissions, version 0 /' "$out/oldperm/instructor/ines.permissions.xml"
resign "$out/oldperm" instructor/ines.permissions
bash "$pkiscript" "$out/oldperm" add instructor ivy >/dev/null
cp "$out/oldperm/instructor/ivy.permissions.xml" "$out/ivy.intact.xml"
sed -i 's|<topic>\*</topic>|<topic>alice.log</topic><topic>bob.log</topic>|; s|<partition>\*</partition>|<partition>alice.log</partition>|' \
  "$out/oldperm/instructor/ivy.permissions.xml"
resign "$out/oldperm" instructor/ivy.permissions
# Such damaged permissions refuse an instructor's every topic: her observer and recorder say what to do
# (they said only "cannot create topic palp_catalogue" and "cannot create a reader: Bad Parameter").
"$client" --role observer --domain 131 --trainee alice --pki "$out/oldperm" --identity instructor/ivy --duration 1 \
  --timeout 3 >"$out/ivy-observer.log" 2>&1
rc=$?
"$recorder" --domain 131 --db "$out/ivy.db" --pki "$out/oldperm" --identity instructor/ivy --duration 1 \
  >"$out/ivy-recorder.log" 2>&1
rc2=$?
"$web" --domain 131 --pki "$out/oldperm" --identity instructor/ivy --port 0 --duration 1 >"$out/ivy-web.log" 2>&1
rc3=$?
check "an instructor whose permissions allow no topic is told at start that they are damaged and, refused, to re-issue them (observer exit $rc, recorder exit $rc2, palp-web exit $rc3)" \
  "[ $rc -ne 0 ] && [ $rc2 -ne 0 ] && [ $rc3 -ne 0 ] && grep -q 'cannot create the bridge.s DDS readers; DDS Security: the permissions of instructor/ivy .* may not allow its topics: re-issue them with scripts/make-classroom-pki.sh .*/oldperm init' '$out/ivy-web.log' && grep -q 'cannot create topic palp_[a-z_]*; DDS Security: the permissions of instructor/ivy (.*/oldperm/instructor/ivy.permissions.p7s) have no rule for topic palp_[a-z_]*: re-issue them with scripts/make-classroom-pki.sh .*/oldperm init' '$out/ivy-observer.log' && grep -q 'WARN  palp-client: DDS Security: the permissions of instructor/ivy name no rule for palp_catalogue, which every palp program reads: they are damaged, and every topic will be refused; re-issue them with scripts/make-classroom-pki.sh .*/oldperm init' '$out/ivy-observer.log' && grep -q 'cannot create a reader: .*; DDS Security: the permissions of instructor/ivy .* may not allow its topics: re-issue them' '$out/ivy-recorder.log'"
bash "$pkiscript" "$out/oldperm" list >"$out/list-before.log" 2>&1
rc=$?
check "list names the older and the damaged permissions and what mends them (exit $rc)" \
  "[ $rc -eq 0 ] && grep -q '^instructor/ines .*; PERMISSIONS OLDER (version 0 of [0-9]*): run init\$' '$out/list-before.log' && grep -q '^instructor/ivy .*; PERMISSIONS DIFFER from what this script issues: run init\$' '$out/list-before.log' && grep -q '^trainee/bob .*; permissions current (version [0-9]*)\$' '$out/list-before.log' && grep -q '^make-classroom-pki: 4 identities. permissions are not what this script issues' '$out/list-before.log'"
(cd "$out" && bash "$pkiscript" oldperm init) >"$out/oldperm-init.log" 2>&1
bash "$pkiscript" "$out/oldperm" list >"$out/list-after.log" 2>&1
check "  ... and after init, every identity's are current" \
  "[ \$(grep -c 'permissions current' '$out/list-after.log') -eq 5 ] && ! grep -q 'PERMISSIONS\\|not what this script' '$out/list-after.log'"
check "init, run where files are, re-issues an instructor's older permissions and mends damaged ones, \"*\" whole" \
  "grep -q '<topic>\*</topic>' '$out/ines.intact.xml' && cmp -s '$out/ines.intact.xml' '$out/oldperm/instructor/ines.permissions.xml' && cmp -s '$out/ivy.intact.xml' '$out/oldperm/instructor/ivy.permissions.xml' && openssl smime -verify -in '$out/oldperm/instructor/ivy.permissions.p7s' -CAfile '$out/oldperm/ca.cert.pem' >/dev/null 2>&1"
check "init re-issues their permissions alone, naming them, with palp_debrief, palp_debrief_score, palp_session_log, palp_finger_sample, palp_session_exercise, palp_session_score and palp_session_closed, signed by the CA" \
  "grep -q 'permissions re-issued (version $pv) for 4 identities (server/server, trainee/alice, instructor/ines, instructor/ivy): copy each' '$out/oldperm-init.log' && grep -q '<topic>palp_session_closed</topic>' '$out/oldperm/server/server.permissions.xml' && ! grep -q 'palp_session_closed' '$out/oldperm/trainee/alice.permissions.xml' && grep -q '<topic>palp_session_log</topic>' '$out/oldperm/trainee/alice.permissions.xml' && grep -q '<topic>palp_session_log</topic>' '$out/oldperm/server/server.permissions.xml' && grep -q '<topic>palp_finger_sample</topic>' '$out/oldperm/trainee/alice.permissions.xml' && grep -q '<topic>palp_finger_sample</topic>' '$out/oldperm/server/server.permissions.xml' && grep -q '<topic>palp_debrief</topic>' '$out/oldperm/trainee/alice.permissions.xml' && grep -q '<topic>palp_debrief_score</topic>' '$out/oldperm/trainee/alice.permissions.xml' && grep -q '<topic>palp_debrief_score</topic>' '$out/oldperm/server/server.permissions.xml' && grep -q '<topic>palp_session_exercise</topic>' '$out/oldperm/server/server.permissions.xml' && grep -q '<topic>palp_session_score</topic>' '$out/oldperm/server/server.permissions.xml' && ! grep -q 'palp_session_exercise\|palp_session_score' '$out/oldperm/trainee/alice.permissions.xml' && openssl smime -verify -in '$out/oldperm/trainee/alice.permissions.p7s' -CAfile '$out/oldperm/ca.cert.pem' >/dev/null 2>&1"
# Re-issued, the server sends each exercise session's exercise, its lesions included, to the
# instructors alone (session 60): a secured palp-recorder (instructor ines) logs alice's attempt at
# "easy" with its exercise, her mark and her debrief as the server's own log has them.
"$recorder" --domain 132 --db "$out/rec-ex.db" --pki "$out/oldperm" --identity instructor/ines --duration 30 \
  >"$out/rec-ex.log" 2>&1 &
rpid=$!
"$server" --domain 132 --config "$(dirname "$0")/server-easy.json" --database "$out/ex.db" \
  --pki "$out/oldperm" --duration 30 >"$out/ex-server.log" 2>&1 &
opid=$!
"$web" --domain 132 --pki "$out/oldperm" --identity instructor/ines --port 0 --no-join --duration 12 \
  >"$out/ex-web.log" 2>&1 &
wpid=$!
# bob, in his own partition palp/s/bob/<her id>, names her session: 2 s of contacts (finger 1) and marks
"$forger" 132 "$out/oldperm" trainee/bob alice 2 >"$out/forger.log" 2>&1 &
fpid=$!
sleep 1
"$client" --role trainee --domain 132 --phantom 11 --pki "$out/oldperm" --identity trainee/alice --duration 3 \
  --timeout 8 --print-period 0 --input sim:press,depth_mm=4,hold_s=1,mark_s=0.5 >"$out/ex.log" 2>&1
wait $fpid
rc=$?
sleep 1.5 # the recorder takes her debrief and the CLOSED state
kill -INT $opid 2>/dev/null
wait $opid
kill -INT $rpid 2>/dev/null
wait $rpid
kill -INT $wpid 2>/dev/null
wait $wpid
check "bob wrote contacts and marks naming alice's session into his own partition (exit $rc): $(cat "$out/forger.log")" \
  "[ $rc -eq 0 ] && grep -q 'forger: [1-9][0-9]* contacts and [1-9][0-9]* marks naming alice.s session [0-9]* written into palp/s/bob/[0-9]*' '$out/forger.log'"
forged=$(python3 - "$out/rec-ex.db" <<'PY' 2>&1
import sqlite3, sys
db = sqlite3.connect(sys.argv[1])
sid = db.execute("select id from session where trainee = 'alice'").fetchone()[0]
fingers = db.execute("select count(*) from contact_input where session_id = ? and slot = 1", (sid,)).fetchone()[0]
ev = db.execute("select coalesce(sum(count), 0) from event where session_id = ? and kind = 'reject' and detail like '%writer outside its partition%'", (sid,)).fetchone()[0]
print("%d %d" % (fingers, ev))
PY
)
check "the secured recorder records none of bob's contacts as alice's, and says it refused them (finger-1 contacts, refused: $forged)" \
  "[ \"\${forged%% *}\" = 0 ] && [ \"\${forged#* }\" -gt 0 ] 2>/dev/null && grep -q 'WARN  palp-recorder: session [0-9]*: a [a-z]* naming it came from a writer in partition palp/s/bob/[0-9]*, not its partition palp/s/alice/[0-9]*: not recorded' '$out/rec-ex.log'"
check "palp-web drops them too, and counts them" \
  "grep -q ' [1-9][0-9]* from outside their session.s partition' '$out/ex-web.log'"
same=$(python3 - "$out/ex.db" "$out/rec-ex.db" <<'PY' 2>&1
import sqlite3, sys
def of(path):
    db = sqlite3.connect(path)
    sid = db.execute("select id from session where trainee = 'alice'").fetchone()[0]
    ex = db.execute("select exercise_json from session_exercise where session_id = ?", (sid,)).fetchone()
    fnd = db.execute("select mark_id, op, point_x_m, point_y_m, point_z_m from finding where session_id = ?", (sid,)).fetchall()
    deb = db.execute("select detail from event where session_id = ? and kind = 'debrief'", (sid,)).fetchall()
    return ex, fnd, deb
a, b = of(sys.argv[1]), of(sys.argv[2])
print("same" if a == b and a[0] and len(a[1]) == 1 and len(a[2]) == 1 else "differ: server %r, recorder %r" % (a[1:], b[1:]))
PY
)
check "a secured recorder logs alice's exercise, mark and debrief as the server does: $same" "[ '$same' = same ]"
# "easy" tells its lesions at the end (a practice exercise): re-issued, alice's station is told her
# score over DDS Security (palp_debrief_score, session 64), the one the server graded from its log.
told=$(sed -n 's/^\[trainee alice\] score: \([0-9.]*\) of 100, \(passed\|not passed\) .*/\1 \2/p' "$out/ex.log" | head -1)
graded=$(sed -n 's/.*session [0-9]* ([^)]*): scored \([0-9.]*\), \(pass\|fail\), from the session log.*/\1 \2/p' "$out/ex-server.log" | sed 's/ pass$/ passed/; s/ fail$/ not passed/' | head -1)
check "alice's station says her score, as the server graded it (station: ${told:-none}; server: ${graded:-none})" \
  "[ -n \"$told\" ] && [ \"$told\" = \"$graded\" ]"
"$client" --role trainee --domain 131 --phantom 1 --pki "$pki" --identity trainee/alice --profile sine --t-on 0 \
  --t-off 60 --duration 8 --print-period 0 >"$out/stall.log" 2>&1 &
cpid=$!
stall_station $cpid "$out/stall.log" 1 1.5
wait $cpid
rc=$?
sid=$(sed -n 's/.*joined session \([0-9]*\).*/\1/p' "$out/stall.log" | head -1)
check "a secured trainee stopped 1.5 s goes on in its session $sid and exits 0 (exit $rc)" \
  "[ $rc -eq 0 ] && [ -n '$sid' ] && grep -q 'did not run for' '$out/stall.log' && grep -q 'session $sid: trainee station trainee/alice/.* came back after' '$out/server.log' && grep -q 'session $sid closed after .* (trainee station left)' '$out/server.log'"
wait $rpid
check "a recorder without an identity says the classroom may be secured, and records nothing" \
  "grep -q 'no phantom from any palp-server in 10 s; .* none of which answered: if the classroom runs with DDS Security' '$out/recorder.log' && grep -q 'stopped; 0 records written' '$out/recorder.log'"
# each recorder's first line says whether it runs secured (since 2026-12-04)
"$recorder" --domain 131 --db "$out/rec2.db" --pki "$pki" --identity instructor/ines --duration 1 >"$out/recorder2.log" 2>&1
rc=$?
check "a recorder says at start whether DDS Security is on, and as whom (exit $rc)" \
  "[ $rc -eq 0 ] && grep -q 'recording domain 131 into .*; DDS Security on (identity instructor/ines)' '$out/recorder2.log' && grep -q 'recording domain 131 into .*; DDS Security off' '$out/recorder.log'"
# ... and, without --domain, the DDS config's default by its number, as the server and the stations
# (loopback config: Domain Id "any", so 0; it said "domain -1" until 2026-12-06). Listens 0.5 s.
"$recorder" --db "$out/rec0.db" --duration 0.5 >"$out/recorder0.log" 2>&1
rc=$?
check "a recorder without --domain names the domain it records (exit $rc)" \
  "[ $rc -eq 0 ] && grep -q 'recording domain 0 (the DDS config.s default) into ' '$out/recorder0.log'"
kill -INT $spid
wait $spid
# make_pki.sh's classroom: alice, bob, ines and the server (dave's files moved to revoked/)
check "the secured server says so when it starts, and how many identities it can name" \
  "grep -q 'DDS Security on: identity server/server, classroom [^ ]*; refused peers are named from 4 classroom certificate(s)' '$out/server.log'"
check "the server's summary has alice's session and counts the refusal" \
  "grep -q 'DDS Security on (identity server/server)' '$out/server.log' && grep -Eq '^1 +alice ' '$out/server.log' && grep -q 'refused request: user_name' '$out/server.log'"
# The plain participants on the secured domain (the recorder and zed's station, both without an
# identity) are named in the server's log once each, by what they announce; no secured one is.
check "the server names the plain recorder and station, once each, and no secured participant" \
  "[ \$(grep -c 'DDS Security refused palp-recorder on host [^ ]* without an identity: a plain DDS participant' '$out/server.log') -eq 1 ] && [ \$(grep -c 'DDS Security refused palp-client on host [^ ]* without an identity' '$out/server.log') -eq 1 ] && [ \$(grep -c 'without an identity' '$out/server.log') -eq 2 ] && grep -q 'DDS Security refused participants [0-9]* time(s): .*palp-client on host [^ ]*: a plain DDS participant' '$out/server.log'"
[ $fail -eq 0 ] || cat "$out/server.log"
rm -rf "$out"
exit $fail

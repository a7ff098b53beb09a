#!/usr/bin/env bash
# make-classroom-pki.sh - the classroom's DDS Security material, made with the OpenSSL CLI:
# a certificate authority, one identity (EC P-256 key + certificate) per participant, the
# governance document and a signed permissions document per identity, and a certificate
# revocation list. docs/security.md explains every rule; Cyclone DDS 0.10 checks them with its
# built-in plugins (libdds_security_{auth,ac,crypto}).
#
#   make-classroom-pki.sh DIR classroom [--trainees a,b] [--instructors c] [--days N]
#                                            CA + governance + CRL + server + the listed identities
#                                            (NAMEs separated by commas; a space is refused)
#   make-classroom-pki.sh DIR init           CA (10 years), governance, empty CRL, identity server
#   make-classroom-pki.sh DIR add KIND NAME [--days N]   KIND: trainee | instructor | server
#   make-classroom-pki.sh DIR revoke KIND/NAME           adds the certificate to DIR/crl.pem (or web/HOST)
#   make-classroom-pki.sh DIR list                       identities, validity, whether their permissions are
#                                                        current (init mends them), revocation
#   make-classroom-pki.sh DIR web HOST[,HOST...] [--days N]   a TLS certificate for palp-web (HTTPS)
#   make-classroom-pki.sh DIR crl                        re-issue the CRL (valid 365 days; palp warns 30 ahead)
#   make-classroom-pki.sh DIR governance                 re-issue the governance (init and classroom
#                                                        do when it is older than this script's)
#
# Layout of DIR (what a station needs is public except its own key):
#   ca.cert.pem                   the classroom CA (identity CA and permissions CA)
#   governance.xml, .p7s          one domain rule for domains 0-230 (the plugin's limit) (signed by the CA)
#   crl.pem                       revoked certificates (signed by the CA; valid 365 days)
#   KIND/NAME.cert.pem, .key.pem  an identity (the key stays on its station, mode 0600)
#   KIND/NAME.permissions.xml, .p7s   what it may publish and subscribe (signed by the CA)
#   web/HOST.cert.pem, .key.pem   palp-web's TLS certificate (no DDS permissions)
#   ca/                           the CA's private key and database: keep it off the stations
#
# A NAME is 1-31 characters of a-z, 0-9, '-' and '_' (it goes into DDS partition names and
# subject names, whose matching treats '*', '?', '[', ',', '/', '=' specially).
set -euo pipefail
set -f # topic and partition patterns contain "*": never expand them as file names

die() { echo "make-classroom-pki: $*" >&2; exit 2; }
[ $# -ge 2 ] || die "usage: $0 DIR classroom|init|add|revoke|list|governance|web|crl ..."
command -v openssl >/dev/null || die "openssl not found (Debian package openssl)"
dir=$1
cmd=$2
shift 2
days=365
# Every palp topic (idl/palp_dds.c). There is no annotation topic: an instructor's
# annotations are written by palp-review into the SQLite log, not over DDS.
T_CATALOGUE=palp_catalogue T_REQUEST=palp_session_request T_REPLY=palp_session_reply
T_STATE=palp_session_state T_CONTACT=palp_contact T_FEEDBACK=palp_feedback
T_DEFORMATION=palp_deformation T_STATUS=palp_server_status
T_LOCAL_MODEL=palp_local_model T_GUARD=palp_server_guard T_IDENTITY=palp_server_identity
T_EXERCISE=palp_exercise T_FINDING=palp_finding T_FINDING_STATUS=palp_finding_status
T_DEBRIEF=palp_debrief T_SESSION_EXERCISE=palp_session_exercise T_SESSION_SCORE=palp_session_score
T_DEBRIEF_SCORE=palp_debrief_score T_SESSION_LOG=palp_session_log T_SESSION_CLOSED=palp_session_closed
T_FINGER_SAMPLE=palp_finger_sample
# palp_station_request (other vendors, docs/interop.md) is not offered by a secured server.

check_name() {
  [[ $1 =~ ^[a-z0-9_-]{1,31}$ ]] || die "bad name \"$1\": 1-31 characters of a-z 0-9 - _"
}
# --trainees / --instructors: NAMEs separated by commas, into the array `names`, each checked. They were
# split on spaces too (for n in ${list//,/ }), so --trainees 'mary ann' made two identities, mary and
# ann (found by review, 2026-12-06): a space, an empty name ("a,,b", a trailing comma) or any other
# character outside NAME's set is refused, before anything is made.
split_names() { # OPTION LIST
  names=()
  local list=$2 n
  [ -n "$list" ] || return 0
  list+=,
  while [ -n "$list" ]; do
    n=${list%%,*}
    list=${list#*,}
    [ -n "$n" ] || die "$1 \"$2\": an empty name (names are separated by single commas, e.g. $1 ann,bob)"
    [[ $n =~ ^[a-z0-9_-]{1,31}$ ]] ||
      die "$1: bad name \"$n\": a NAME is 1-31 characters of a-z 0-9 - _, and names are separated by commas (no spaces): e.g. $1 mary-ann,bob"
    names+=("$n")
  done
}
check_kind() {
  case $1 in trainee | instructor | server) ;; *) die "bad kind \"$1\": trainee, instructor or server" ;; esac
}

# text <<EOF: the here-document on stdout, as cat prints it, without starting cat (a classroom's script run
# started ~20 of them, a fifth of its programs; session 84).
text() {
  local line
  while IFS= read -r line; do printf '%s\n' "$line"; done
}

# The CA's openssl configuration names the CA's directory by its absolute path, so it is written for the
# directory this run works on, at the start of every command that signs or revokes (ca_ready), not only by
# init: until session 81 only init wrote it, and a copied PKI (cp -a) signed with and revoked into the
# ORIGINAL's ca/serial and index.txt, a moved one could not sign at all, and a copy's init then issued
# serials the original had already used (a new trainee born revoked).
write_ca_config() {
  [ -d "$dir/ca/newcerts" ] || mkdir -p "$dir/ca/newcerts"
  chmod 700 "$dir/ca"
  [ -f "$dir/ca/index.txt" ] || : >"$dir/ca/index.txt"
  [ -f "$dir/ca/serial" ] || echo 1000 >"$dir/ca/serial"
  [ -f "$dir/ca/crlnumber" ] || echo 1000 >"$dir/ca/crlnumber"
  text >"$dir/ca/ca.cnf" <<EOF
# written by make-classroom-pki.sh for $dir at each of its runs: copy or move DIR freely, then run the
# script on the new DIR (never openssl ca -config with a copied ca.cnf: it names the directory it came from)
[ ca ]
default_ca = classroom
[ classroom ]
dir = $dir/ca
database = \$dir/index.txt
new_certs_dir = \$dir/newcerts
certificate = $dir/ca.cert.pem
private_key = \$dir/ca.key.pem
serial = \$dir/serial
crlnumber = \$dir/crlnumber
default_md = sha256
default_days = 365
# A CRL past its nextUpdate fails every certificate check (OpenSSL X509_V_FLAG_CRL_CHECK):
# re-issue it (any revoke does) well within this period.
default_crl_days = 365
policy = classroom_policy
unique_subject = no
copy_extensions = none
x509_extensions = identity_ext
[ classroom_policy ]
organizationName = supplied
organizationalUnitName = supplied
commonName = supplied
[ identity_ext ]
basicConstraints = critical, CA:FALSE
keyUsage = critical, digitalSignature, keyAgreement
subjectKeyIdentifier = hash
authorityKeyIdentifier = keyid
EOF
}

# Before a command that signs or revokes with the CA (add, revoke, crl, web): the CA is there, with the
# database openssl keeps (a new, empty one would re-issue serials already used and forget revocations),
# and its configuration names this DIR.
ca_ready() {
  [ -f "$dir/ca/ca.key.pem" ] || die "$dir: no CA; run '$0 $dir init' first"
  [ -f "$dir/ca/index.txt" ] && [ -f "$dir/ca/serial" ] ||
    die "$dir/ca: the CA's database (index.txt, serial) is missing: restore $dir/ca/ from its backup"
  write_ca_config
}

sign() { # xml -> p7s, S/MIME signed by the CA (what Cyclone's access control plugin reads)
  openssl smime -sign -in "$1" -text -out "$2" -signer "$dir/ca.cert.pem" -inkey "$dir/ca/ca.key.pem"
}

# cert_info CERT: what this script reads of a certificate, from one openssl run and one date run: cert_serial
# ("serial=HEX"), cert_end (its notAfter as openssl prints it), cert_nb_utc and cert_na_utc (its validity as
# the permissions' UTC times). Each identity took five openssl x509 runs, four cut and four date (of ~17
# processes an identity, 2026-12-07: a 5-identity classroom 4.2 s of CPU, 135 programs started; with the
# here-documents printed by text, 54 programs, 1.55 s).
# Returns 1 when the certificate cannot be read.
cert_info() {
  local out line nb="" na="" utc
  cert_serial="" cert_end="" cert_nb_utc="" cert_na_utc=""
  out=$(openssl x509 -in "$1" -noout -serial -startdate -enddate) || return 1
  while IFS= read -r line; do
    case $line in
    serial=*) cert_serial=$line ;;
    notBefore=*) nb=${line#notBefore=} ;;
    notAfter=*) na=${line#notAfter=} ;;
    esac
  done <<<"$out"
  [ -n "$cert_serial" ] && [ -n "$nb" ] && [ -n "$na" ] || return 1
  cert_end=$na
  utc=$(printf '%s\n%s\n' "$nb" "$na" | date -u -f - +%Y-%m-%dT%H:%M:%S) || return 1
  cert_nb_utc=${utc%%$'\n'*} cert_na_utc=${utc#*$'\n'}
}

# The governance's version: init and classroom re-issue an older one (docs/security.md,
# "Stations of another vendor"). 2: the topics stations write carry a submessage MAC (SIGN).
GOVERNANCE_VERSION=2
# The permissions' version: init and classroom re-issue every identity's older permissions (same
# validity as its certificate). 2 (2026-12-05): palp_debrief, server -> the trainee's session.
# 3 (2026-12-05, session 60): palp_session_exercise, server -> instructors (the lesions).
# 4 (2026-12-05, session 63): palp_session_score, server -> instructors (a closed session's score).
# 5 (2026-12-05, session 64): palp_debrief_score, server -> the trainee's session (a practice
# exercise's score, after a debrief that told the lesions).
# 6 (2026-12-06, session 69): palp_session_log, server -> the trainee's session (the records of her
# session the server's log lost; without it her station counts the whole server's).
# 7 (2026-12-06, session 69): palp_session_closed, server -> instructors (who each closed session was,
# for a dashboard begun after it).
# 8 (2026-12-06, session 71): palp_finger_sample, server -> the trainee's session (the assessment's
# finger samples with the touched triangles; without it her coverage is approximated from the
# local models).
# palp's programs warn at start of permissions older than their PALP_DDS_PERMISSIONS_VERSION
# (idl/palp_dds_security.h): raise both together (test security_cli checks they agree).
PERMISSIONS_VERSION=8

topic_rule() { # topic expression, metadata protection kind
  text <<EOF
        <topic_rule>
          <topic_expression>$1</topic_expression>
          <enable_discovery_protection>true</enable_discovery_protection>
          <enable_liveliness_protection>true</enable_liveliness_protection>
          <enable_read_access_control>true</enable_read_access_control>
          <enable_write_access_control>true</enable_write_access_control>
          <metadata_protection_kind>$2</metadata_protection_kind>
          <data_protection_kind>ENCRYPT</data_protection_kind>
        </topic_rule>
EOF
}

governance() {
  # Authenticated discovery and liveliness (encrypted), every RTPS message signed, every
  # topic's data encrypted (AES-GCM: also authenticated), read and write access control on.
  # Submessages: the topics a station or an instructor writes (requests, contacts, findings)
  # carry a MAC of their own (SIGN). The RTPS message's signature already authenticates them
  # for palp's own stations, but Fast DDS 2.x (ROS 2's default DDS) matches its writer with a
  # reader only once it holds the reader's crypto tokens, and Cyclone DDS 0.10 sends none for a
  # reader without submessage protection: with NONE here a Fast DDS station reads everything
  # and none of its requests or contacts reach the server (test interop_fastdds_secure). The
  # topics the server writes at up to 1 kHz (feedback, local models) keep NONE: one MAC fewer
  # per sample on the hot path, and a Fast DDS reader needs only the writer's tokens, which
  # the encrypted payload brings. The first matching rule applies.
  {
    text <<EOF
<?xml version="1.0" encoding="utf-8"?>
<!-- palp classroom governance, version $GOVERNANCE_VERSION (scripts/make-classroom-pki.sh) -->
<dds xmlns:xsi="http://www.w3.org/2001/XMLSchema-instance"
     xsi:noNamespaceSchemaLocation="http://www.omg.org/spec/DDS-SECURITY/20170901/omg_shared_ca_governance.xsd">
  <domain_access_rules>
    <domain_rule>
      <domains><id_range><min>0</min><max>230</max></id_range></domains>
      <allow_unauthenticated_participants>false</allow_unauthenticated_participants>
      <enable_join_access_control>true</enable_join_access_control>
      <discovery_protection_kind>ENCRYPT</discovery_protection_kind>
      <liveliness_protection_kind>ENCRYPT</liveliness_protection_kind>
      <rtps_protection_kind>SIGN</rtps_protection_kind>
      <topic_access_rules>
EOF
    topic_rule "$T_REQUEST" SIGN
    topic_rule "$T_CONTACT" SIGN
    topic_rule "$T_FINDING" SIGN
    topic_rule "*" NONE
    text <<'EOF'
      </topic_access_rules>
    </domain_rule>
  </domain_access_rules>
</dds>
EOF
  } >"$dir/governance.xml"
  sign "$dir/governance.xml" "$dir/governance.p7s"
}

governance_current() { grep -q "palp classroom governance, version $GOVERNANCE_VERSION " "$dir/governance.xml" 2>/dev/null; }

# rule publish|subscribe "topic ..." "partition ..." ("" = the default partition)
# Split into words with read -a, never by unquoted expansion: a pattern such as "*" or "palp/s/*"
# must stay a pattern whatever the shell's globbing state and the caller's directory.
rule() {
  local what=$1 t p topics parts
  read -r -a topics <<<"$2"
  read -r -a parts <<<"$3"
  echo "        <$what>"
  echo "          <topics>"
  for t in "${topics[@]}"; do echo "            <topic>$t</topic>"; done
  echo "          </topics>"
  echo "          <partitions>"
  for p in "${parts[@]}"; do
    if [ "$p" = '""' ]; then echo "            <partition></partition>"; else echo "            <partition>$p</partition>"; fi
  done
  echo "          </partitions>"
  echo "        </$what>"
}

permissions_xml() { # kind name not_before not_after
  local kind=$1 name=$2
  {
    text <<EOF
<?xml version="1.0" encoding="utf-8"?>
<!-- palp permissions, version $PERMISSIONS_VERSION (scripts/make-classroom-pki.sh) -->
<dds xmlns:xsi="http://www.w3.org/2001/XMLSchema-instance"
     xsi:noNamespaceSchemaLocation="http://www.omg.org/spec/DDS-SECURITY/20170901/omg_shared_ca_permissions.xsd">
  <permissions>
    <grant name="$kind-$name">
      <subject_name>CN=$name,OU=$kind,O=palp</subject_name>
      <validity>
        <not_before>$3</not_before>
        <not_after>$4</not_after>
      </validity>
      <allow_rule>
        <domains><id_range><min>0</min><max>230</max></id_range></domains>
EOF
    case $kind in
    server)
      # Only the server publishes the catalogue, replies, states, status and every session's
      # feedback and deformation; it reads requests from every identity's own partition.
      rule publish "$T_CATALOGUE $T_REPLY $T_STATE $T_STATUS $T_GUARD $T_IDENTITY $T_EXERCISE $T_SESSION_EXERCISE $T_SESSION_SCORE $T_SESSION_CLOSED" '""'
      rule publish "$T_FEEDBACK $T_DEFORMATION $T_LOCAL_MODEL $T_FINDING_STATUS $T_DEBRIEF $T_DEBRIEF_SCORE $T_SESSION_LOG $T_FINGER_SAMPLE" "palp/s/*"
      rule subscribe "$T_REQUEST" "palp/trainee/* palp/instructor/*"
      rule subscribe "$T_CONTACT $T_FINDING" "palp/s/*"
      rule subscribe "$T_STATUS $T_GUARD $T_IDENTITY" '""'
      ;;
    trainee)
      # Requests only in its own partition (the server reads the identity from it), contacts
      # only into its own sessions ("palp/s/NAME/<id>"); reads the public state and its own
      # sessions' traffic, nobody else's.
      rule publish "$T_REQUEST" "palp/trainee/$name"
      rule publish "$T_CONTACT $T_FINDING" "palp/s/$name/*"
      rule subscribe "$T_CATALOGUE $T_REPLY $T_STATE $T_STATUS $T_GUARD $T_IDENTITY $T_EXERCISE" '""'
      rule subscribe "$T_CONTACT $T_FEEDBACK $T_DEFORMATION $T_LOCAL_MODEL $T_FINDING $T_FINDING_STATUS $T_DEBRIEF $T_DEBRIEF_SCORE $T_SESSION_LOG $T_FINGER_SAMPLE" \
        "palp/s/$name/*"
      ;;
    instructor)
      # Reads everything; writes only its own requests (joins as observer or visual station).
      rule publish "$T_REQUEST" "palp/instructor/$name"
      rule subscribe "*" '"" *'
      ;;
    esac
    text <<EOF
      </allow_rule>
      <default>DENY</default>
    </grant>
  </permissions>
</dds>
EOF
  }
}

# --days: a whole number of days, at least 1, and never past the classroom CA's own end: openssl signs a
# certificate that outlives its CA (40000 days under a 10-year CA verified "OK"), and every peer refuses
# it once the CA has expired anyway (session 75, found by review).
# One openssl run decides (-checkend: the CA still valid DAYS from now), once a run, not once an identity;
# the CA's end and the days left to it are read only for the message of a refusal (or a --days too long to
# multiply), where they decide as before: DAYS at most the whole days left.
ca_ok_days=""
check_days() {
  [[ $days =~ ^[0-9]+$ ]] && [ "$days" -ge 1 ] || die "--days: expected a positive integer, got '$days'"
  [ -f "$dir/ca.cert.pem" ] || return 0
  [ "$ca_ok_days" != "$days" ] || return 0
  if [ ${#days} -le 6 ] && openssl x509 -in "$dir/ca.cert.pem" -noout -checkend $((days * 86400)) >/dev/null; then
    ca_ok_days=$days
    return 0
  fi
  local end left now
  end=$(openssl x509 -in "$dir/ca.cert.pem" -noout -enddate)
  end=${end#notAfter=}
  printf -v now '%(%s)T' -1
  left=$((($(date -d "$end" +%s) - now) / 86400))
  [ "$days" -le "$left" ] ||
    die "--days $days: past the classroom CA's own end ($end, $left days from now); issue for at most $left days"
  ca_ok_days=$days
}

add() { # kind name
  local kind=$1 name=$2
  check_kind "$kind"
  check_name "$name"
  [ -f "$dir/ca/ca.key.pem" ] || die "$dir: no CA; run '$0 $dir init' first"
  check_days
  [ -d "$dir/$kind" ] || mkdir -p "$dir/$kind"
  local base="$dir/$kind/$name"
  (umask 077 && openssl ecparam -name prime256v1 -genkey -noout -out "$base.key.pem")
  openssl req -new -key "$base.key.pem" -subj "/O=palp/OU=$kind/CN=$name" -out "$base.csr" 2>/dev/null
  openssl ca -batch -config "$dir/ca/ca.cnf" -days "$days" -notext -in "$base.csr" -out "$base.cert.pem" 2>/dev/null ||
    die "signing $kind/$name failed"
  rm -f "$base.csr"
  cert_info "$base.cert.pem" || die "$kind/$name: cannot read the certificate just signed"
  permissions_of "$kind" "$name"
  echo "make-classroom-pki: $kind/$name: $cert_serial until $cert_end"
}

# The permissions this script issues for KIND/NAME (stdout), valid exactly as long as its certificate.
# Here and in the two below, the caller has read that certificate (cert_info).
permissions_for() { # kind name
  permissions_xml "$1" "$2" "$cert_nb_utc" "$cert_na_utc"
}

# ... written and signed by the CA.
permissions_of() { # kind name
  local xml="$dir/$1/$2.permissions.xml"
  permissions_for "$1" "$2" >"$xml"
  sign "$xml" "$dir/$1/$2.permissions.p7s"
}

# 0 when KIND/NAME's permissions are what this script issues; 1 when they are missing; 2 when they
# differ (older, or damaged).
permissions_current() { # kind name
  local base="$dir/$1/$2"
  [ -f "$base.permissions.xml" ] && [ -f "$base.permissions.p7s" ] || return 1
  permissions_for "$1" "$2" | cmp -s - "$base.permissions.xml" || return 2
}

# Every current identity whose permissions differ from what this script issues gets them re-issued:
# older than PERMISSIONS_VERSION (a topic added to palp needs a rule: a station's older permissions
# cannot create it), or damaged (until 2026-12-06 a re-issue run from a directory holding files wrote
# an instructor's "*" as those files' names, and its stations could then create no topic).
permissions_refresh() {
  local c kind name n=0 certs who=""
  # File names are expanded here only: the rules written below hold "*" (an instructor reads every
  # topic), which with expansion on became the names of the files in the caller's directory.
  set +f
  certs=("$dir"/server/*.cert.pem "$dir"/trainee/*.cert.pem "$dir"/instructor/*.cert.pem)
  set -f
  for c in "${certs[@]}"; do
    [ -f "$c" ] || continue
    kind=${c%/*} name=${c##*/}
    kind=${kind##*/} name=${name%.cert.pem}
    cert_info "$c" || die "$c: cannot read it (openssl x509)"
    permissions_current "$kind" "$name" && continue
    permissions_of "$kind" "$name"
    n=$((n + 1)) who="$who${who:+, }$kind/$name"
  done
  # named, so that whoever copies them knows which machines to visit
  [ "$n" -eq 0 ] ||
    echo "make-classroom-pki: permissions re-issued (version $PERMISSIONS_VERSION) for $n identities ($who): copy each $dir/KIND/NAME.permissions.p7s to its station and restart them and the server"
}

# A TLS server certificate for palp-web (docs/web.md, "HTTPS"), signed by the classroom CA, so that a
# browser which trusts ca.cert.pem reaches the dashboard over HTTPS. HOSTS: the names and addresses
# the pages are opened by (subjectAltName; browsers ignore the CN). Its key stays on palp-web's
# machine; it has no DDS permissions, so it cannot join the classroom's domain.
web_cert() {
  local hosts=$1 first san="" h base
  [[ $hosts =~ ^[A-Za-z0-9.:,-]+$ ]] || die "web: bad hosts \"$hosts\": DNS names or IP addresses, separated by commas"
  check_days
  first=${hosts%%,*}
  for h in ${hosts//,/ }; do
    if [[ $h =~ ^[0-9]{1,3}(\.[0-9]{1,3}){3}$ || $h =~ ^[0-9a-fA-F:]+$ && $h == *:* ]]; then
      san+="${san:+,}IP:$h"
    elif [[ $h =~ ^[A-Za-z0-9]([A-Za-z0-9.-]{0,251}[A-Za-z0-9])?$ ]]; then
      san+="${san:+,}DNS:$h"
    else
      die "web: bad host \"$h\": a DNS name or an IP address"
    fi
  done
  [ -n "$san" ] || die "usage: $0 DIR web HOST[,HOST...] [--days N]"
  ca_ready
  mkdir -p "$dir/web"
  base="$dir/web/$(echo "$first" | tr ':' '_')"
  # The new key and certificate are made beside the ones there and moved into place together once the
  # certificate is signed: until session 90 the key was written over in place first, so a signing that
  # failed left the old certificate beside a new key it does not match (palp-web then refused to start;
  # found by review).
  rm -f "$base.new.key.pem" "$base.new.cert.pem"
  (umask 077 && openssl ecparam -name prime256v1 -genkey -noout -out "$base.new.key.pem")
  openssl req -new -key "$base.new.key.pem" -subj "/O=palp/OU=web/CN=$first" -out "$base.csr" 2>/dev/null
  text >"$base.ext" <<EOF
[ web_ext ]
basicConstraints = critical, CA:FALSE
keyUsage = critical, digitalSignature
extendedKeyUsage = serverAuth
subjectAltName = $san
subjectKeyIdentifier = hash
authorityKeyIdentifier = keyid
EOF
  if ! openssl ca -batch -config "$dir/ca/ca.cnf" -days "$days" -notext -extfile "$base.ext" -extensions web_ext \
    -in "$base.csr" -out "$base.new.cert.pem" 2>/dev/null || ! cert_info "$base.new.cert.pem"; then
    rm -f "$base.new.key.pem" "$base.new.cert.pem" "$base.csr" "$base.ext"
    die "signing the web certificate for $first failed (the key and certificate already there, if any, are kept)"
  fi
  rm -f "$base.csr" "$base.ext"
  mv -f "$base.new.key.pem" "$base.key.pem" && mv -f "$base.new.cert.pem" "$base.cert.pem" ||
    die "web/${base##*/}: cannot move the new key and certificate into place"
  echo "make-classroom-pki: web/${base##*/}: $san until $cert_end"
  echo "make-classroom-pki: palp-web --tls-cert $base.cert.pem --tls-key $base.key.pem; browsers must trust $dir/ca.cert.pem"
}

# The CRL is written beside the old one and moved into place: a failed run leaves the old CRL whole and
# says why (its errors went to /dev/null and the script just stopped, so a revoke whose CRL failed left
# the identity accepted with nothing said; session 75).
crl() {
  local err
  if ! err=$(openssl ca -config "$dir/ca/ca.cnf" -gencrl -out "$dir/crl.pem.new" 2>&1); then
    rm -f "$dir/crl.pem.new" 2>/dev/null || true
    die "the CRL was not issued: ${err//$'\n'/ }; mend that, then run '$0 $dir crl' (a revoked identity stays accepted until $dir/crl.pem names it)"
  fi
  mv -f "$dir/crl.pem.new" "$dir/crl.pem"
}

init() {
  mkdir -p "$dir"
  dir=$(cd "$dir" && pwd)
  write_ca_config
  if [ ! -f "$dir/ca/ca.key.pem" ]; then
    # made under a temporary name and moved: an interrupted run leaves no key that looks like a CA's
    (umask 077 && openssl ecparam -name prime256v1 -genkey -noout -out "$dir/ca/ca.key.pem.new" &&
      mv -f "$dir/ca/ca.key.pem.new" "$dir/ca/ca.key.pem")
  fi
  if [ ! -f "$dir/ca.cert.pem" ]; then
    # A key without its certificate (a run stopped between the two, before session 75 every later run
    # then failed when signing): the certificate is made from that key; nobody can hold one made before.
    openssl req -x509 -new -key "$dir/ca/ca.key.pem" -subj "/O=palp/OU=ca/CN=palp classroom CA" -days 3650 \
      -sha256 -out "$dir/ca.cert.pem.new" && mv -f "$dir/ca.cert.pem.new" "$dir/ca.cert.pem" ||
      die "the CA certificate was not made"
    echo "make-classroom-pki: CA $dir/ca.cert.pem (key in $dir/ca/, keep it off the stations)"
  fi
  if [ ! -f "$dir/governance.p7s" ]; then
    governance
  elif ! governance_current; then
    governance
    echo "make-classroom-pki: governance re-issued (version $GOVERNANCE_VERSION): copy $dir/governance.p7s to every station and restart them and the server"
  fi
  [ -f "$dir/crl.pem" ] || crl
  [ -f "$dir/server/server.cert.pem" ] || add server server
  permissions_refresh
}

case $cmd in
init) init ;;
governance)
  dir=$(cd "$dir" && pwd)
  [ -f "$dir/ca/ca.key.pem" ] || die "$dir: no CA; run '$0 $dir init' first"
  governance
  echo "make-classroom-pki: governance version $GOVERNANCE_VERSION in $dir/governance.p7s: copy it to every station and restart them and the server"
  ;;
classroom)
  trainees="" instructors=""
  while [ $# -gt 0 ]; do
    case $1 in
    --trainees) trainees=${2:-}; shift 2 ;;
    --instructors) instructors=${2:-}; shift 2 ;;
    --days) days=${2:-}; shift 2 ;;
    *) die "classroom: unknown option $1" ;;
    esac
  done
  split_names --trainees "$trainees"
  trainee_names=("${names[@]}")
  split_names --instructors "$instructors"
  instructor_names=("${names[@]}")
  init
  for n in "${trainee_names[@]}"; do [ -f "$dir/trainee/$n.cert.pem" ] || add trainee "$n"; done
  for n in "${instructor_names[@]}"; do [ -f "$dir/instructor/$n.cert.pem" ] || add instructor "$n"; done
  ;;
add)
  [ $# -ge 2 ] || die "usage: $0 DIR add KIND NAME [--days N]"
  kind=$1 name=$2
  shift 2
  [ "${1:-}" = --days ] && days=${2:?--days N}
  [[ $days =~ ^[0-9]+$ ]] && [ "$days" -ge 1 ] || die "--days: expected a positive integer"
  dir=$(cd "$dir" && pwd)
  check_kind "$kind"
  check_name "$name"
  [ ! -f "$dir/$kind/$name.cert.pem" ] || die "$kind/$name exists; revoke it first to re-issue"
  ca_ready
  add "$kind" "$name"
  ;;
revoke)
  [ $# -eq 1 ] || die "usage: $0 DIR revoke KIND/NAME"
  # Only an identity or a palp-web certificate, named as this script names them: KIND/NAME, or web/HOST
  # (the certificate's file name: its first host, ':' as '_'). Anything else was taken as a path under DIR
  # until session 81: 'revoke ca' revoked the CA's own certificate, moved ca.cert.pem into revoked/ and
  # broke every later add. Refused before anything changes.
  case $1 in
  */*) kind=${1%%/*} name=${1#*/} ;;
  *) die "revoke: \"$1\" is not an identity: give KIND/NAME (KIND trainee, instructor or server; e.g. trainee/alice) or web/HOST (a palp-web certificate, as 'list' names it)" ;;
  esac
  if [ "$kind" = web ]; then
    [[ $name =~ ^[A-Za-z0-9_][A-Za-z0-9._-]{0,252}$ ]] ||
      die "revoke: bad web certificate \"$name\": web/HOST, HOST as $dir/web/HOST.cert.pem names it"
  else
    check_kind "$kind"
    check_name "$name"
  fi
  dir=$(cd "$dir" && pwd)
  cert="$dir/$kind/$name.cert.pem"
  [ -f "$cert" ] || die "no identity $1 in $dir"
  ca_ready
  # Again after a revoke whose CRL failed (the CA's index already says revoked): finished, not refused.
  if ! err=$(openssl ca -config "$dir/ca/ca.cnf" -revoke "$cert" 2>&1); then
    case $err in
    *"Already revoked"*) echo "make-classroom-pki: $1 was already revoked in the CA's index (a revoke that stopped before its CRL): finishing it" ;;
    *) die "revoking $1 failed: ${err//$'\n'/ }" ;;
    esac
  fi
  crl
  # The revoked files are kept aside (for the record), so the name can be issued again.
  mkdir -p "$dir/revoked"
  set +f
  stamp=$(date -u +%Y%m%dT%H%M%S)
  # Only this name's own files: a web HOST may hold dots, and "$1".* also matched every host named
  # HOST.SOMETHING (revoking web/lab moved lab.local's certificate and key; until session 82).
  for ext in cert.pem key.pem permissions.xml permissions.p7s csr ext; do
    f="$dir/$1.$ext"
    [ -e "$f" ] && mv "$f" "$dir/revoked/$(echo "$1" | tr / _)-$stamp.$ext"
  done
  echo "make-classroom-pki: $1 revoked; distribute $dir/crl.pem to every station and restart the server"
  ;;
crl)
  # Re-issued whenever a certificate is revoked; also by hand before it expires (default_crl_days,
  # 365): an expired CRL fails every handshake. palp warns 30 days ahead.
  dir=$(cd "$dir" && pwd)
  ca_ready
  crl
  echo "make-classroom-pki: $dir/crl.pem re-issued, next update $(openssl crl -in "$dir/crl.pem" -noout -nextupdate | cut -d= -f2); copy it to every participant"
  ;;
web)
  [ $# -ge 1 ] || die "usage: $0 DIR web HOST[,HOST...] [--days N]"
  hosts=$1
  shift
  [ "${1:-}" = --days ] && days=${2:?--days N}
  [[ $days =~ ^[0-9]+$ ]] && [ "$days" -ge 1 ] || die "--days: expected a positive integer"
  dir=$(cd "$dir" && pwd)
  web_cert "$hosts"
  ;;
list)
  # Each identity with its serial, its expiry and whether its permissions are what this script issues
  # (older or damaged ones: "init" re-issues them); then the revoked ones and palp-web's certificates.
  dir=$(cd "$dir" && pwd)
  set +f
  certs=("$dir"/server/*.cert.pem "$dir"/trainee/*.cert.pem "$dir"/instructor/*.cert.pem)
  revoked=("$dir"/revoked/*.cert.pem)
  webs=("$dir"/web/*.cert.pem)
  set -f
  stale=0
  for c in "${certs[@]}"; do
    [ -f "$c" ] || continue
    kind=${c%/*} name=${c##*/}
    kind=${kind##*/} name=${name%.cert.pem}
    st=0
    cert_info "$c" || cert_serial="serial=?" cert_end="? (openssl cannot read it)"
    permissions_current "$kind" "$name" || st=$?
    v=$(sed -n 's/^<!-- palp permissions, version \([0-9]*\) .*/\1/p' "$dir/$kind/$name.permissions.xml" 2>/dev/null)
    case $st in
    0) perm="permissions current (version $PERMISSIONS_VERSION)" ;;
    1) perm="NO PERMISSIONS: run init" ;;
    *) if [ -n "$v" ] && [ "$v" -lt "$PERMISSIONS_VERSION" ]; then
         perm="PERMISSIONS OLDER (version $v of $PERMISSIONS_VERSION): run init"
       else
         perm="PERMISSIONS DIFFER from what this script issues: run init"
       fi ;;
    esac
    [ "$st" -eq 0 ] || stale=$((stale + 1))
    echo "$kind/$name  $cert_serial until $cert_end; $perm"
  done
  [ "$stale" -eq 0 ] || echo "make-classroom-pki: $stale identities' permissions are not what this script issues: '$0 $dir init' re-issues them"
  echo "revoked (crl.pem):"
  openssl crl -in "$dir/crl.pem" -noout -text | grep -E "Serial Number" || echo "  none"
  for c in "${revoked[@]}"; do
    if [ -f "$c" ]; then echo "  kept aside: revoked/$(basename "$c" .cert.pem)  $(openssl x509 -in "$c" -noout -serial)"; fi
  done
  for c in "${webs[@]}"; do
    if [ -f "$c" ]; then echo "palp-web TLS: web/$(basename "$c" .cert.pem)  until $(openssl x509 -in "$c" -noout -enddate | cut -d= -f2)"; fi
  done
  ;;
*) die "unknown command $cmd" ;;
esac

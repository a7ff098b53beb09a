#!/bin/sh
# Makes the security tests' certificates at run time, into the build tree:
#   DIR          the classroom: trainees alice, bob and dave (dave then revoked), instructor ines
#   DIR-dave     dave's own copy of his files, kept before the revocation, with the CRL of then
#                (a revoked station does not volunteer its own revocation; palp refuses a PKI
#                without any crl.pem since session 81)
#   DIR-forged   bob's genuine identity with permissions granting the server's rights, signed by
#                a CA of his own (DIR-rogue) instead of the classroom's
#   DIR-thief    bob's certificate and permissions, copied (they are public), with a private key
#                of the thief's own: an impersonation the handshake's signature must expose
#   DIR-rogue    the other CA, with a trainee alice of its own (cli.sh: a certificate another classroom's
#                CA issued; it made a third classroom of its own for it until session 84)
# usage: make_pki.sh make-classroom-pki.sh DIR
set -eu
script=$1
dir=$2
rm -rf "$dir" "$dir-dave" "$dir-rogue" "$dir-forged" "$dir-thief"
bash "$script" "$dir" classroom --trainees alice,bob,dave --instructors ines >/dev/null
mkdir -p "$dir-dave/trainee"
cp "$dir/ca.cert.pem" "$dir/governance.p7s" "$dir/crl.pem" "$dir-dave/"
cp "$dir/trainee/dave.cert.pem" "$dir/trainee/dave.key.pem" "$dir/trainee/dave.permissions.p7s" "$dir-dave/trainee/"
bash "$script" "$dir" revoke trainee/dave >/dev/null
openssl crl -in "$dir/crl.pem" -noout -text | grep -q "Serial Number" || { echo "make_pki: dave not in the CRL" >&2; exit 1; }

bash "$script" "$dir-rogue" classroom --trainees alice >/dev/null
mkdir -p "$dir-forged/trainee"
cp "$dir/ca.cert.pem" "$dir/crl.pem" "$dir-forged/"
cp "$dir-rogue/ca.cert.pem" "$dir-forged/rogue-ca.cert.pem"
cp "$dir-rogue/governance.p7s" "$dir-forged/governance.p7s"
cp "$dir/trainee/bob.cert.pem" "$dir/trainee/bob.key.pem" "$dir-forged/trainee/"
sed 's/CN=server,OU=server,O=palp/CN=bob,OU=trainee,O=palp/' "$dir-rogue/server/server.permissions.xml" \
  >"$dir-forged/trainee/bob.permissions.xml"
grep -q "CN=bob,OU=trainee" "$dir-forged/trainee/bob.permissions.xml"
openssl smime -sign -in "$dir-forged/trainee/bob.permissions.xml" -text -out "$dir-forged/trainee/bob.permissions.p7s" \
  -signer "$dir-rogue/ca.cert.pem" -inkey "$dir-rogue/ca/ca.key.pem"

mkdir -p "$dir-thief/trainee"
cp "$dir/ca.cert.pem" "$dir/governance.p7s" "$dir/crl.pem" "$dir-thief/"
cp "$dir/trainee/bob.cert.pem" "$dir/trainee/bob.permissions.p7s" "$dir-thief/trainee/"
(umask 077 && openssl ecparam -name prime256v1 -genkey -noout -out "$dir-thief/trainee/bob.key.pem")
echo "make_pki: $dir ready"

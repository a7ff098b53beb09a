#!/bin/bash
# scripts/make-classroom-pki.sh when things go wrong (session 75, a review's findings; no DDS, openssl only):
#  - --days past the classroom CA's own end is refused, and nothing is issued (openssl signed a
#    certificate for 40000 days under a 10-year CA, and it verified); a non-number is refused;
#  - a revoke whose CRL cannot be written (here: a directory where the new CRL goes) says so, exit 2,
#    and leaves the old CRL byte-identical; run again once mended it finishes the revoke (the CA's
#    index already said revoked, which made the second run fail for good before): the CRL names the
#    serial and the files are moved aside;
#  - a CA key without its certificate (a run stopped between the two) is completed by init: the
#    certificate made from that key, and a trainee issued after it verifies against it;
#  - (2026-12-06) classroom's --trainees and --instructors are split on commas only: 'mary ann' (split
#    on the space into mary and ann before), an empty name, a capital, a '.', '*' are refused, exit 2,
#    naming the name, before anything is made (no directory); 'mary-ann,bob' makes exactly those
#    identities, CN=mary-ann.
#  - (session 81) a copied PKI signs and revokes in its own CA database, the original's untouched; a moved
#    one signs; the new certificates verify with their CRL; serials stay distinct. revoke refuses anything
#    but KIND/NAME or web/HOST ('revoke ca' moved the CA certificate away), exit 2, nothing changed.
#  - (session 82) revoke web/lab moves lab's certificate and key only, not lab.local's.
# usage: pki_script.sh MAKE_CLASSROOM_PKI_SH
set -u
script=$1
out=$(mktemp -d)
fail=0
check() { if eval "$2"; then echo "ok   $1"; else echo "FAIL $1"; fail=1; fi; }
pki=$out/class

bash "$script" "$pki" classroom --trainees ann --days 40000 >"$out/days.log" 2>&1
rc=$?
check "--days 40000 under a 10-year CA: refused (exit $rc), named, nothing issued for ann" \
  "[ $rc -eq 2 ] && grep -q \"past the classroom CA's own end (.*, 36[0-9][0-9] days from now); issue for at most 36[0-9][0-9] days\" '$out/days.log' && [ ! -e '$pki/trainee/ann.cert.pem' ]"
bash "$script" "$pki" add trainee bea --days 3x >"$out/days2.log" 2>&1
rc=$?
check "--days 3x: refused (exit $rc)" "[ $rc -eq 2 ] && grep -q 'expected a positive integer' '$out/days2.log'"
bash "$script" "$pki" add trainee bea --days 30 >"$out/bea.log" 2>&1
rc=$?
ends=$(openssl x509 -in "$pki/trainee/bea.cert.pem" -noout -enddate 2>/dev/null | cut -d= -f2)
left=$((($(date -d "${ends:-now}" +%s) - $(date +%s)) / 86400))
check "--days 30: issued (exit $rc), valid 29-30 days from now ($left)" "[ $rc -eq 0 ] && [ $left -ge 29 ] && [ $left -le 30 ]"

serial=$(openssl x509 -in "$pki/trainee/bea.cert.pem" -noout -serial | cut -d= -f2)
sum0=$(md5sum <"$pki/crl.pem")
mkdir "$pki/crl.pem.new" # where the new CRL is written: a directory, so writing it fails
bash "$script" "$pki" revoke trainee/bea >"$out/revoke1.log" 2>&1
rc=$?
sum1=$(md5sum <"$pki/crl.pem")
check "a revoke whose CRL cannot be written: exit $rc, says so, the old CRL untouched, bea's files where they were" \
  "[ $rc -eq 2 ] && grep -q 'the CRL was not issued: .*run .* crl. (a revoked identity stays accepted until .*crl.pem names it)' '$out/revoke1.log' && [ '$sum0' = '$sum1' ] && [ -f '$pki/trainee/bea.cert.pem' ]"
rmdir "$pki/crl.pem.new"
bash "$script" "$pki" revoke trainee/bea >"$out/revoke2.log" 2>&1
rc=$?
check "run again once mended: finished (exit $rc), the CRL names serial $serial, bea's files moved aside" \
  "[ $rc -eq 0 ] && grep -q 'was already revoked in the CA.s index .*: finishing it' '$out/revoke2.log' && openssl crl -in '$pki/crl.pem' -noout -text | grep -q 'Serial Number: $serial' && [ ! -e '$pki/trainee/bea.cert.pem' ] && ls '$pki'/revoked/trainee_bea-*.cert.pem >/dev/null 2>&1"

half=$out/half
bash "$script" "$half" init >/dev/null 2>&1
rm -f "$half/ca.cert.pem"
bash "$script" "$half" init >"$out/half.log" 2>&1
rc=$?
bash "$script" "$half" add trainee cai >/dev/null 2>&1
same=$( [ "$(openssl x509 -in "$half/ca.cert.pem" -noout -pubkey 2>/dev/null)" = "$(openssl ec -in "$half/ca/ca.key.pem" -pubout 2>/dev/null)" ] && echo yes)
check "a CA key without its certificate: init makes it from that key (exit $rc, same key: ${same:-no}), a trainee issued then verifies" \
  "[ $rc -eq 0 ] && [ '$same' = yes ] && openssl verify -CAfile '$half/ca.cert.pem' '$half/trainee/cai.cert.pem' >/dev/null 2>&1"
names=$out/names
for bad in "mary ann" "ann,,bob" "ann," "Ann" "a.b" "a*"; do
  bash "$script" "$names" classroom --trainees "$bad" --instructors ines >"$out/names.log" 2>&1
  rc=$?
  case $bad in *,,* | *,) want="an empty name" ;; *) want="bad name \"$bad\"" ;; esac
  check "--trainees '$bad': refused (exit $rc), named, nothing made" \
    "[ $rc -eq 2 ] && grep -qF -- '$want' '$out/names.log' && [ ! -e '$names' ]"
done
bash "$script" "$names" classroom --instructors "ines bridge" >"$out/names.log" 2>&1
rc=$?
check "--instructors 'ines bridge': refused (exit $rc), nothing made" \
  "[ $rc -eq 2 ] && grep -qF 'bad name \"ines bridge\"' '$out/names.log' && [ ! -e '$names' ]"
bash "$script" "$names" classroom --trainees mary-ann,bob --instructors ines >"$out/names.log" 2>&1
rc=$?
made=$(cd "$names" 2>/dev/null && ls trainee/*.cert.pem instructor/*.cert.pem 2>/dev/null | tr '\n' ' ')
cn=$(openssl x509 -in "$names/trainee/mary-ann.cert.pem" -noout -subject 2>/dev/null)
check "--trainees mary-ann,bob --instructors ines: exit $rc, exactly those identities ($made), $cn" \
  "[ $rc -eq 0 ] && [ '$made' = 'instructor/ines.cert.pem trainee/bob.cert.pem trainee/mary-ann.cert.pem ' ] && echo '$cn' | grep -q 'CN *= *mary-ann$'"

# (session 81) A copied or moved PKI signs and revokes with its OWN CA database: ca/ca.cnf named the
# directory init ran in, and only init rewrote it, so a copy (cp -a) signed with and revoked into the
# original's ca/serial and index.txt, and a moved one could not sign at all.
orig=$out/orig
bash "$script" "$orig" classroom --trainees ann,bea >/dev/null 2>&1
cp -a "$orig" "$out/copy"
copy=$out/copy
state() { (cd "$1" && md5sum ca/serial ca/index.txt crl.pem | tr '\n' ' '); }
o0=$(state "$orig") c0=$(state "$copy")
bash "$script" "$copy" add trainee cid >"$out/copy-add.log" 2>&1
rc1=$?
ann_serial=$(openssl x509 -in "$copy/trainee/ann.cert.pem" -noout -serial | cut -d= -f2)
bash "$script" "$copy" revoke trainee/ann >"$out/copy-revoke.log" 2>&1
rc2=$?
o1=$(state "$orig") c1=$(state "$copy")
check "a copy (cp -a) adds (exit $rc1) and revokes (exit $rc2) in its own ca/serial, index.txt and crl.pem; the original's untouched" \
  "[ $rc1 -eq 0 ] && [ $rc2 -eq 0 ] && [ '$o0' = '$o1' ] && [ '$c0' != '$c1' ] && grep -q 'CN=cid' '$copy/ca/index.txt' && ! grep -q 'CN=cid' '$orig/ca/index.txt' && grep -q '^R.*CN=ann' '$copy/ca/index.txt' && ! grep -q '^R' '$orig/ca/index.txt' && openssl crl -in '$copy/crl.pem' -noout -text | grep -q 'Serial Number: $ann_serial'"
bash "$script" "$copy" add trainee dan >"$out/copy-add2.log" 2>&1
rc=$?
v=$(openssl verify -crl_check -CAfile "$copy/ca.cert.pem" -CRLfile "$copy/crl.pem" "$copy/trainee/dan.cert.pem" 2>&1)
vann=$(openssl verify -crl_check -CAfile "$copy/ca.cert.pem" -CRLfile "$copy/crl.pem" "$copy"/revoked/trainee_ann-*.cert.pem 2>&1)
serials=$(cut -f4 "$copy/ca/index.txt" | sort | tr '\n' ' ')
dups=$(cut -f4 "$copy/ca/index.txt" | sort | uniq -d | tr '\n' ' ')
check "the copy's next trainee (exit $rc) verifies with the copy's CRL ($v), the revoked ann does not; serials all distinct ($serials)" \
  "[ $rc -eq 0 ] && [ '$v' = '$copy/trainee/dan.cert.pem: OK' ] && ! echo '$vann' | grep -q ': OK\$' && [ -z '$dups' ] && [ \$(echo $serials | wc -w) -eq 5 ]"
mv "$orig" "$out/moved"
moved=$out/moved
bash "$script" "$moved" add trainee eve >"$out/moved-add.log" 2>&1
rc=$?
v=$(openssl verify -crl_check -CAfile "$moved/ca.cert.pem" -CRLfile "$moved/crl.pem" "$moved/trainee/eve.cert.pem" 2>&1)
dups=$(cut -f4 "$moved/ca/index.txt" | sort | uniq -d | tr '\n' ' ')
serials=$(cut -f4 "$moved/ca/index.txt" | sort | tr '\n' ' ')
check "a moved PKI adds (exit $rc: $(tr '\n' ' ' <"$out/moved-add.log" | cut -c1-120)), verifies with its CRL ($v), serials distinct ($serials)" \
  "[ $rc -eq 0 ] && [ '$v' = '$moved/trainee/eve.cert.pem: OK' ] && [ -z '$dups' ] && [ \$(echo $serials | wc -w) -eq 4 ] && [ ! -e '$orig' ]"
bash "$script" "$moved" crl >/dev/null 2>&1 && bash "$script" "$moved" web lab-host >/dev/null 2>&1
rc=$?
check "a moved PKI re-issues its CRL and makes a web certificate (exit $rc)" \
  "[ $rc -eq 0 ] && openssl verify -crl_check -CAfile '$moved/ca.cert.pem' -CRLfile '$moved/crl.pem' '$moved/web/lab-host.cert.pem' >/dev/null 2>&1"

# (session 81) revoke takes only KIND/NAME or web/HOST: 'revoke ca' exited 0, moved ca.cert.pem into
# revoked/ and broke every later add. Each refused with exit 2, nothing changed in DIR.
tree() { (cd "$1" && find . -type f -exec md5sum {} + | sort | md5sum); }
t0=$(tree "$moved")
for bad in ca ca/ca.key ca.cert.pem trainee trainee/ /trainee/bea trainee/Bea "trainee/bea/../../ca" \
           ../ca student/bea web/ "web/../ca" "web/.x"; do
  bash "$script" "$moved" revoke "$bad" >"$out/badrevoke.log" 2>&1
  rc=$?
  check "revoke '$bad': refused (exit $rc: $(head -c 150 "$out/badrevoke.log")), nothing changed" \
    "[ $rc -eq 2 ] && grep -qE 'is not an identity: give KIND/NAME|bad kind|bad name|bad web certificate' '$out/badrevoke.log' && [ '$t0' = \"\$(tree '$moved')\" ]"
done
bash "$script" "$moved" add trainee fay >/dev/null 2>&1
rc1=$?
bash "$script" "$moved" revoke web/lab-host >"$out/webrevoke.log" 2>&1
rc2=$?
check "after them, add still signs (exit $rc1); revoke web/lab-host revokes palp-web's certificate (exit $rc2)" \
  "[ $rc1 -eq 0 ] && [ $rc2 -eq 0 ] && [ -f '$moved/ca.cert.pem' ] && [ ! -e '$moved/web/lab-host.cert.pem' ] && ls '$moved'/revoked/web_lab-host-*.cert.pem >/dev/null 2>&1"

# (session 82) revoke web/HOST moves HOST's own files only: "HOST".* also matched lab.local's
# certificate and key when web/lab was revoked, and palp-web serving lab.local lost them.
bash "$script" "$moved" web lab >/dev/null 2>&1 && bash "$script" "$moved" web lab.local >/dev/null 2>&1
rc1=$?
ll0=$(cat "$moved/web/lab.local.cert.pem" "$moved/web/lab.local.key.pem" 2>/dev/null | md5sum)
bash "$script" "$moved" revoke web/lab >"$out/webrevoke2.log" 2>&1
rc2=$?
ll1=$(cat "$moved/web/lab.local.cert.pem" "$moved/web/lab.local.key.pem" 2>/dev/null | md5sum)
moved_lab=$(ls "$moved"/revoked/ | grep -c '^web_lab-[0-9T]*\.' || true)
moved_local=$(ls "$moved"/revoked/ | grep -c '^web_lab-[0-9T]*\.local' || true)
check "revoke web/lab (exit $rc1, $rc2): lab's certificate and key moved aside ($moved_lab files), lab.local's left in web/ unchanged ($moved_local moved)" \
  "[ $rc1 -eq 0 ] && [ $rc2 -eq 0 ] && [ ! -e '$moved/web/lab.cert.pem' ] && [ ! -e '$moved/web/lab.key.pem' ] && [ -f '$moved/web/lab.local.cert.pem' ] && [ -f '$moved/web/lab.local.key.pem' ] && [ '$ll0' = '$ll1' ] && [ $moved_lab -eq 2 ] && [ $moved_local -eq 0 ]"
# (session 90) web HOST again whose signing fails (the CA's serial file damaged): palp-web's key and
# certificate there are kept as a matching pair (the key was written over first, and a failed signing
# left the old certificate beside a new key), and no half-made file is left
ll2=$(cat "$moved/web/lab.local.cert.pem" "$moved/web/lab.local.key.pem" 2>/dev/null | md5sum)
cp "$moved/ca/serial" "$out/serial.bak" && echo "not a serial" >"$moved/ca/serial"
bash "$script" "$moved" web lab.local >"$out/webfail.log" 2>&1
rc=$?
cp "$out/serial.bak" "$moved/ca/serial"
ll3=$(cat "$moved/web/lab.local.cert.pem" "$moved/web/lab.local.key.pem" 2>/dev/null | md5sum)
left=$(ls "$moved/web" | grep -c '\.new\.' || true)
check "web lab.local again, its signing failing (exit $rc: $(head -c 120 "$out/webfail.log")): its key and certificate kept ($left new files left)" \
  "[ $rc -ne 0 ] && [ '$ll2' = '$ll3' ] && [ $left -eq 0 ] && openssl x509 -noout -in '$moved/web/lab.local.cert.pem' && [ \"\$(openssl x509 -noout -pubkey -in '$moved/web/lab.local.cert.pem')\" = \"\$(openssl pkey -pubout -in '$moved/web/lab.local.key.pem')\" ]"
rm -rf "$out"
exit $fail

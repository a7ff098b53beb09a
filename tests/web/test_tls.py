#!/usr/bin/env python3
"""web_tls: palp-web over HTTPS and WSS with a certificate from the classroom CA (docs/web.md, "HTTPS").

The token is palp-web's whole authentication; on a class network it must not cross the wire in clear.
- palp-web refuses to serve beyond loopback without TLS (exit 2, before binding), a certificate without
  its key, an unreadable file, a key that is not the certificate's (named as such, before libwebsockets
  is given it: web/tls.c), and a key or token file every user of the machine can read;
- a certificate with a day left is served, with a warning at start that says when it expires;
- scripts/make-classroom-pki.sh DIR web 127.0.0.1,localhost issues the certificate;
- a client that trusts the classroom CA gets the pages over HTTPS (200; the cookie is Secure), nothing
  without the token (401), and the WebSocket over WSS ("hello"); one that trusts only the system's CAs
  is refused by its own TLS check; plain HTTP on the port gets no page;
- headless Chromium that trusts exactly that certificate's key (--ignore-certificate-errors-spki-list)
  opens the trainee page over HTTPS, which connects its stream over WSS and draws; without that trust
  the page never loads.
DDS domain 127. usage: test_tls.py BUILD SOURCE OUT"""
import base64
import hashlib
import os
import re
import socket
import ssl
import subprocess
import time
import urllib.error

import harness
from harness import check

TOKEN = "tls-test-token-0123456789"


def spki_sha256(cert):
    """base64 SHA-256 of the certificate's SubjectPublicKeyInfo (what Chromium pins)."""
    pub = subprocess.run(["openssl", "x509", "-in", cert, "-pubkey", "-noout"], capture_output=True, check=True).stdout
    der = subprocess.run(["openssl", "pkey", "-pubin", "-outform", "der"], input=pub, capture_output=True,
                         check=True).stdout
    return base64.b64encode(hashlib.sha256(der).digest()).decode()


def run(build, source, out):
    procs = harness.Procs(build, source, out, 127)
    browsers = []
    try:
        exe = os.path.join(build, "web", "palp-web")
        pki = os.path.join(out, "pki")
        subprocess.run(["rm", "-rf", pki], check=True)
        script = os.path.join(source, "scripts", "make-classroom-pki.sh")
        r = subprocess.run(["bash", script, pki, "init"], capture_output=True, text=True, timeout=60)
        check(r.returncode == 0, "classroom CA made (exit %d)" % r.returncode)
        r = subprocess.run(["bash", script, pki, "web", "127.0.0.1,localhost"], capture_output=True, text=True,
                           timeout=60)
        cert, key = os.path.join(pki, "web", "127.0.0.1.cert.pem"), os.path.join(pki, "web", "127.0.0.1.key.pem")
        check(r.returncode == 0 and os.path.exists(cert) and (os.stat(key).st_mode & 0o077) == 0,
              "make-classroom-pki.sh web: certificate, key mode 0600: %s" % r.stdout.strip().splitlines()[0])
        ca = os.path.join(pki, "ca.cert.pem")

        def refused(args, want, why, code=2):
            r = subprocess.run([exe, "--port", "0", "--domain", "127"] + args, capture_output=True, text=True,
                               timeout=20, env=procs.env)
            check(r.returncode == code and want in r.stderr + r.stdout,
                  "%s: exit %d: %s" % (why, r.returncode, (r.stderr + r.stdout).strip()[:110]))

        for addr in ["0.0.0.0", "::"]:
            refused(["--listen", addr, "--token", TOKEN], "without TLS", "--listen %s with a token but no TLS" % addr)
        refused(["--tls-cert", cert, "--token", TOKEN], "go together", "a certificate without its key")
        refused(["--tls-cert", cert, "--tls-key", os.path.join(pki, "nope.pem")], "No such file",
                "an unreadable key")
        # checked before libwebsockets is given them (web/tls.c): exit 2, the reason named (libwebsockets
        # said "must be PEM and belong together (the port may also be in use ...)", exit 1, and leaked)
        refused(["--tls-cert", cert, "--tls-key", os.path.join(pki, "server", "server.key.pem")],
                "is not the key of", "another key than the certificate's")
        refused(["--tls-cert", key, "--tls-key", key], "not a PEM certificate", "the key given as the certificate")

        open_key = os.path.join(pki, "open.key.pem")
        subprocess.run(["cp", key, open_key], check=True)
        os.chmod(open_key, 0o644)
        refused(["--tls-cert", cert, "--tls-key", open_key], "readable by every user", "a world-readable key")
        tokf = os.path.join(pki, "token.txt")
        with open(tokf, "w") as f:
            f.write(TOKEN + "\n")
        os.chmod(tokf, 0o604)
        refused(["--token-file", tokf], "readable by every user", "a world-readable --token-file")

        # --insecure-http overrides the rule, with a warning: run in a network namespace of its own with only
        # "lo" (unshare -n), so that 0.0.0.0 reaches nothing but loopback.
        r = subprocess.run(["unshare", "-n", "sh", "-c", "ip link set lo up && exec \"$@\"", "sh", exe, "--listen",
                            "0.0.0.0", "--port", "0", "--domain", "127", "--no-join", "--token", TOKEN,
                            "--insecure-http", "--duration", "1"], capture_output=True, text=True, timeout=30,
                           env=procs.env)
        check(r.returncode == 0 and "serving plain HTTP on 0.0.0.0 (--insecure-http)" in r.stdout + r.stderr
              and "http://0.0.0.0:" in r.stdout,
              "--insecure-http serves plain HTTP beyond loopback and warns (in a namespace with only lo; exit %d)"
              % r.returncode)

        # a certificate in its last month: palp-web serves, and says at start when to renew it
        r = subprocess.run(["bash", script, pki, "web", "localhost", "--days", "1"], capture_output=True, text=True,
                           timeout=60)
        soon_cert, soon_key = os.path.join(pki, "web", "localhost.cert.pem"), os.path.join(pki, "web", "localhost.key.pem")
        r = subprocess.run([exe, "--port", "0", "--domain", "127", "--no-join", "--token", TOKEN, "--tls-cert",
                            soon_cert, "--tls-key", soon_key, "--duration", "1"], capture_output=True, text=True,
                           timeout=30, env=procs.env)
        m = re.search(r"expires in ([0-9.]+) day\(s\)", r.stdout + r.stderr)
        check(r.returncode == 0 and m is not None and 0.9 <= float(m.group(1)) <= 1.0 and "WARN" in r.stdout + r.stderr,
              "a certificate with 1 day left: served (exit %d), and a warning says when: %s" %
              (r.returncode, m.group(0) if m else (r.stdout + r.stderr)[-200:]))

        procs.server()
        procs.trainee("alice", 1, ["--profile", "step", "--magnitude", "2", "--t-on", "0.5", "--t-off", "60",
                                   "--duration", "60"])
        web = procs.start("web", [exe, "--domain", "127", "--port", "0", "--token", TOKEN, "--tls-cert", cert,
                                  "--tls-key", key])
        port = int(procs.wait_log(web, r"serving HTTPS on \S+ port (\d+)", 20).group(1))
        check("https://127.0.0.1:%d/dashboard.html" % port in procs.log(web), "it prints https:// addresses")
        base = "https://127.0.0.1:%d" % port
        trust = ssl.create_default_context(cafile=ca)
        status, body, headers = harness.http_get(base + "/trainee.html?token=" + TOKEN, context=trust)
        cookie = headers.get("Set-Cookie", "")
        check(status == 200 and b"trainee" in body and "Secure" in cookie and "HttpOnly" in cookie,
              "HTTPS, trusting the classroom CA: the page (%d) and a Secure, HttpOnly cookie" % status)
        status, body, _ = harness.http_get(base + "/trainee.html", context=trust)
        check(status == 401 and b"trainee" not in body, "HTTPS without the token: %d, none of the page" % status)
        try:
            harness.http_get(base + "/trainee.html?token=" + TOKEN, context=ssl.create_default_context())
            verified = False
        except urllib.error.URLError as e:
            verified = isinstance(e.reason, ssl.SSLCertVerificationError)
        check(verified, "a client trusting only the system's CAs refuses the certificate (its own TLS check)")
        got = b""
        try:
            with socket.create_connection(("127.0.0.1", port), timeout=5) as s:
                s.sendall(b"GET /trainee.html?token=" + TOKEN.encode() + b" HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n")
                s.settimeout(3)
                while len(got) < 65536:
                    chunk = s.recv(4096)
                    if not chunk:
                        break
                    got += chunk
        except OSError:
            pass
        check(b"200 OK" not in got and b"trainee" not in got,
              "plain HTTP to the HTTPS port: no page (%d bytes back)" % len(got))

        ws = harness.cdp.WebSocket("wss://127.0.0.1:%d/ws?token=%s" % (port, TOKEN), timeout=10, ssl_context=trust)
        op, data = ws.recv()
        ws.close()
        check(op == 1 and data.startswith(b'{"type":"hello"'), "WSS with the token: hello")

        pin = spki_sha256(cert)
        browser = harness.cdp.Chromium(out_dir=out, extra_args=["--ignore-certificate-errors-spki-list=" + pin])
        browsers.append(browser)
        page = browser.new_page(base + "/trainee.html?token=" + TOKEN)
        ok = page.wait_for("window.palpState && palpState.connected && palpState.trainee.rendered > 0", 25)
        proto = page.eval("location.protocol")
        page.screenshot(os.path.join(out, "tls-trainee.png"))
        check(ok is True and proto == "https:",
              "Chromium trusting the certificate's key: the trainee page over %s, its stream over WSS, drawing" % proto)
        browsers.pop().close()
        plain = harness.cdp.Chromium(out_dir=out)
        browsers.append(plain)
        page = plain.new_page(base + "/trainee.html?token=" + TOKEN)
        time.sleep(2.0)
        # Polled, not read once: under load Chromium may still be swapping in its certificate
        # error page after 2 s, and an evaluation then finds no execution context at all.
        state = page.wait_for("JSON.stringify({state: typeof window.palpState, canvas: "
                              "document.querySelectorAll('canvas').length})", 20) or ""
        check('"state":"undefined"' in state and '"canvas":0' in state,
              "Chromium without that trust: the page does not load: %s" % state)
    finally:
        for b in browsers:
            b.close()
        procs.close()


if __name__ == "__main__":
    harness.main(run)

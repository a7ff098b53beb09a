# tests/chromium.sh - sourced by the report tests (tests/db/test_report.sh,
# tests/review/test_review_cli.sh): Debian's headless Chromium with no network at all (every
# host name resolves to nothing; file:// needs none) and a throw-away profile.
# palp_chromium_render HTML PNG DOM LOG WIDTHxHEIGHT: a screenshot and the DOM after scripts.
palp_chromium=/usr/bin/chromium
palp_chromium_profile=$(mktemp -d)
trap 'rm -rf "$palp_chromium_profile"' EXIT
# As root, without CAP_SYS_NICE: Chromium would raise its threads to nice -8 and starve the suite's
# other tests (tests/web/cdp.py, NO_RAISE).
palp_no_raise=
[ "$(id -u)" = 0 ] && palp_no_raise="/usr/bin/setpriv --bounding-set=-sys_nice --"
palp_chromium_run() {
  # shellcheck disable=SC2086 # palp_no_raise is a command prefix, split on purpose
  timeout 90 $palp_no_raise "$palp_chromium" --headless --no-sandbox --disable-gpu --disable-quic --no-first-run \
    --disable-background-networking --disable-component-update --disable-sync --disable-extensions \
    --no-proxy-server "--host-resolver-rules=MAP * ~NOTFOUND" --user-data-dir="$palp_chromium_profile" "$@"
}
# One Chromium for both (the DOM on stdout, its log on stderr): each start costs ~1.5 s of CPU, and
# the two had been two starts (2026-12-07).
palp_chromium_render() {
  palp_chromium_run --window-size="$(echo "$5" | tr x ,)" --screenshot="$2" --dump-dom "file://$1" >"$3" 2>"$4"
}
# palp_chromium_render_many WIDTHxHEIGHT LOG HTML PNG DOM [HTML PNG DOM ...]: the same for several pages in one
# Chromium, over DevTools (tests/chromium_render.py; the three reports of test_review_cli.sh had been three starts).
palp_chromium_render_many() {
  # (sourced by a script in tests/AREA/: its $0's folder)
  timeout 150 /usr/bin/python3 "$(dirname "$0")/../chromium_render.py" "$@"
}

# Sourced by the scripts that set up, build, test or run palp (setup.sh, test.sh, demo.sh, fuzz.sh,
# sanitize.sh): the Debian packages' own programs first on PATH. The scripts install and test against
# the packages in scripts/debian-packages.txt; a version manager's shims ahead of them on root's PATH
# would run other builds than those, and slowly: pyenv's python3 shim took 0.33 s of CPU a start
# against 0.03 s for Debian's /usr/bin/python3 (2026-12-07), over the many python3 starts of a test
# run (every browser test, the review and report checks, each `python3 -` in the shell tests).
case ":$PATH:" in
  :/usr/sbin:/usr/bin:/sbin:/bin:*) ;;
  *) PATH=/usr/sbin:/usr/bin:/sbin:/bin:$PATH; export PATH ;;
esac

# Sourced by the interop tests (fastdds.sh, fastdds_secure.sh): their private network namespace, the
# work directory and the result helpers.
#
# in_private_netns "$0" "$@": re-runs the test in a network namespace of its own with only "lo"
# (unshare -n), so that neither DDS stack can send anywhere but loopback whatever its defaults; if
# unshare is not permitted it says so and the test runs on the host's loopback (both stacks are
# configured unicast, 127.0.0.1 only).
in_private_netns() {
  script=$1
  shift
  if [ "${PALP_IN_NETNS:-}" != 1 ]; then
    if unshare -n true 2> /dev/null; then
      echo "ok   private network namespace (unshare -n): only lo"
      exec env PALP_IN_NETNS=1 unshare -n sh "$script" "$@"
    fi
    echo "NOTE unshare -n is not permitted here: running on the host's loopback"
  else
    ip link set lo up 2> /dev/null || { echo "FAIL cannot bring lo up in the namespace"; exit 1; }
  fi
}

# work_dir PREFIX: a fresh $work, removed (and the server $spid stopped) on exit.
work_dir() {
  work=$(mktemp -d -t "$1.XXXXXX") # under TMPDIR (scripts/test.sh gives the tests one of their own)
  spid=
  trap '[ -n "$spid" ] && kill "$spid" 2>/dev/null; rm -rf "$work"' EXIT
}

fail=0
ok() { echo "ok   $*"; }
bad() { echo "FAIL $*"; fail=1; }
# r NAME KEY: the value of "result KEY VALUE" in $work/NAME.out (fastdds_station's output)
r() { sed -n "s/^result $2 //p" "$work/$1.out" | head -1; }
num_ge() { awk -v a="$1" -v b="$2" 'BEGIN { exit !(a + 0 >= b + 0) }'; }
num_in() { awk -v a="$1" -v lo="$2" -v hi="$3" 'BEGIN { exit !(a + 0 >= lo + 0 && a + 0 <= hi + 0) }'; }

# check_finger_samples NAME: the assessment's finger samples (palp_finger_sample, session 71: a bounded
# sequence of touched-triangle ids) as fastdds_station read them over its 1.6 s press by position: one
# every lround(physics / 100 Hz) steps (the session log's sampling, every step at 100 Hz or less), so
# the nearest step between two read is that; best-effort, so at least 60% of them; every sample in
# contact names 1-256 triangles of the catalogue's mesh.
check_finger_samples() {
  hz=$(r "$1" physics_hz)
  want=$(awk -v h="$hz" 'BEGIN { k = h > 100 ? int(h / 100 + 0.5) : 1; print k }')
  least=$(awk -v h="$hz" -v k="$want" 'BEGIN { printf "%d", 0.6 * 1.6 * h / k }')
  if num_ge "$(r "$1" fsm_samples)" "$least" && num_ge "$(r "$1" fsm_in_contact)" 20 \
     && [ "$(r "$1" fsm_touching)" = "$(r "$1" fsm_in_contact)" ] && num_in "$(r "$1" fsm_tri_max)" 1 256 \
     && [ "$(r "$1" fsm_bad_ids)" = 0 ] && [ "$(r "$1" fsm_step_min)" = "$want" ]; then
    ok "palp_finger_sample read by Fast DDS: $(r "$1" fsm_samples) samples (>= $least), $(r "$1" fsm_in_contact) in contact, each naming 1-$(r "$1" fsm_tri_max) triangles of the mesh; frames $(r "$1" fsm_step_min)-$(r "$1" fsm_step_max) steps apart at $hz Hz (want $want)"
  else
    bad "palp_finger_sample through Fast DDS: $(r "$1" fsm_samples) samples (want >= $least), $(r "$1" fsm_in_contact) in contact, $(r "$1" fsm_touching) naming triangles, at most $(r "$1" fsm_tri_max), $(r "$1" fsm_bad_ids) ids off the mesh, frames $(r "$1" fsm_step_min)-$(r "$1" fsm_step_max) steps apart at $hz Hz (want $want)"
  fi
}

# check_press NAME: fastdds_station's 3 N press (distribution II, pole, 1.5 s) as seen in $work/NAME.out.
# The phantom pushes back with the applied load once the press has settled (docs/model.md: within 5%
# from 0.03 s), so 1.5 s in the feedback reads 3 N within 5%; the default long-term dome dents
# 0.37-0.6 mm under the 3 N patch (the FEM 0.5 mm, docs/materials.md; a dome at rest stays under
# 0.01 mm), so the meshes show at least 0.2 mm; the NaN force sample is counted as rejected for its
# reason, nonfinite (the server's status per session and reason; the session state's rejected_samples sums
# every reason, so any earlier rejection satisfied it until session 83), and for no other reason.
# Feedback flows for most of the press: at least 20 samples and one for every second turn of the station's
# 100 Hz loop (a contact sent each turn); until 2026-12-07 at least 50, which a station starved at the suite's
# busiest start (64 turns in the 1.5 s, 43 samples) failed with the feedback flowing.
check_press() {
  local sent
  sent=$(r "$1" contacts_sent)
  num_in "$(r "$1" feedback_last_N)" 2.85 3.15 && num_ge "$(r "$1" feedback_samples)" 20 \
    && num_ge "$(r "$1" feedback_samples)" "$(( ${sent:-0} / 2 ))" \
    && ok "feedback: $(r "$1" feedback_samples) samples for $sent contacts sent, last |F| $(r "$1" feedback_last_N) N (3 N press, want within 5%)" \
    || bad "feedback: $(r "$1" feedback_samples) samples for $sent contacts sent, last |F| $(r "$1" feedback_last_N) N"
  [ "$(r "$1" deformation_vertices)" = 338 ] && num_ge "$(r "$1" deformation_samples)" 10 \
    && num_ge "$(r "$1" deformation_max_mm)" 0.2 \
    && ok "deformation: $(r "$1" deformation_samples) meshes of 338 vertices, max displacement $(r "$1" deformation_max_mm) mm" \
    || bad "deformation: $(r "$1" deformation_samples) samples, $(r "$1" deformation_vertices) vertices, $(r "$1" deformation_max_mm) mm"
  set -- $(r "$1" rejected_reasons) "$(r "$1" rejected_samples)"
  if [ $# -eq 3 ] && num_ge "$1" 1 && [ "$2" = 0 ] && num_ge "$3" 1; then
    ok "NaN sample rejected by the server as nonfinite ($1 in the status for reason 0, $2 for the other nine; $3 in the session state)"
  else
    bad "NaN sample not rejected as nonfinite: reasons \"$1 $2\" (nonfinite, others), $3 in the session state"
  fi
}

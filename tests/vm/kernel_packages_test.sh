#!/usr/bin/env bash
# Usage: kernel_packages_test.sh
# kernel_packages.sh's choice and deb_cache.sh's cache, on canned apt outputs
# (testdata/apt/DAY, read through FLOWSTEER_APT_CANNED; no network):
#   captured-2026-11-28   apt-cache's outputs on that day: linux-kbuild-6.1 6.1.192-2 no longer
#                         served, 6.1.192-3 taken (it satisfies the headers' >= 6.1.192-2), and
#                         linux-source-6.1 6.1.192-2, the image's own, over the newer 6.1.192-3;
#   day-before-2026-11-27 the same with kbuild 6.1.192-2 still served and source 6.1.192-3 not
#                         yet: every package of the image's own version;
#   fallback-to-bookworm  security's newest kernel (6.1.194-1) without its -common headers yet:
#                         bookworm main's 6.1.176-1, whole;
#   nothing-fits          no kbuild new enough for 6.1.192-2, no source for 6.1.176-1: an error
#                         naming both and the commands that show them;
#   deb-cache             a fake .deb of a version with an epoch and its stanza: fetched under
#                         apt-get download's name, used again, a cut-short copy detected and
#                         fetched again, a corrupt download refused.
# Prints every mismatch and exits 1 if there was any.
set -euo pipefail

here=$(cd "$(dirname "$0")" && pwd)
data=$here/testdata/apt
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
failures=0

fail() {
  echo "FAIL: $*" >&2
  failures=$((failures + 1))
}

# check_choice DAY EXPECTED: kernel_packages.sh on DAY's outputs prints EXPECTED.
check_choice() {
  local actual
  if ! actual=$(FLOWSTEER_APT_CANNED=$data/$1 "$here/kernel_packages.sh" 2> "$work/stderr"); then
    fail "$1: kernel_packages.sh failed: $(cat "$work/stderr")"
  elif [[ $actual != "$2" ]]; then
    fail "$1: kernel_packages.sh chose"$'\n'"$actual"$'\n'"instead of"$'\n'"$2"
  fi
}

# check_error DAY TEXT...: kernel_packages.sh on DAY's outputs fails, with each TEXT in its
# message.
check_error() {
  local day=$1 text
  shift
  if FLOWSTEER_APT_CANNED=$data/$day "$here/kernel_packages.sh" > "$work/stdout" \
    2> "$work/stderr"; then
    fail "$day: kernel_packages.sh chose, where it should have failed:"$'\n'"$(cat "$work/stdout")"
    return
  fi
  for text in "$@"; do
    grep -qF -- "$text" "$work/stderr" ||
      fail "$day: the error lacks '$text'; it reads:"$'\n'"$(cat "$work/stderr")"
  done
}

check_choice captured-2026-11-28 "\
image linux-image-6.1.0-56-amd64 6.1.192-2
headers linux-headers-6.1.0-56-amd64 6.1.192-2
common linux-headers-6.1.0-56-common 6.1.192-2
kbuild linux-kbuild-6.1 6.1.192-3
source linux-source-6.1 6.1.192-2"
check_choice day-before-2026-11-27 "\
image linux-image-6.1.0-56-amd64 6.1.192-2
headers linux-headers-6.1.0-56-amd64 6.1.192-2
common linux-headers-6.1.0-56-common 6.1.192-2
kbuild linux-kbuild-6.1 6.1.192-2
source linux-source-6.1 6.1.192-2"
check_choice fallback-to-bookworm "\
image linux-image-6.1.0-50-amd64 6.1.176-1
headers linux-headers-6.1.0-50-amd64 6.1.176-1
common linux-headers-6.1.0-50-common 6.1.176-1
kbuild linux-kbuild-6.1 6.1.176-1
source linux-source-6.1 6.1.176-1"
check_error nothing-fits \
  "linux-image-amd64 6.1.192-2 (linux-image-6.1.0-56-amd64): no linux-kbuild-6.1 of 6.1.192 satisfying >= 6.1.192-2 is served (apt-cache madison linux-kbuild-6.1)" \
  "linux-image-amd64 6.1.176-1 (linux-image-6.1.0-50-amd64): no linux-source-6.1 of 6.1.176 is served (apt-cache madison linux-source-6.1)"
check_error no-such-day "apt-cache knows no linux-image-amd64 (run apt-get update)"

# The cache, in a subshell: deb_cache.sh is sourced, with the canned archive and a fresh cache.
(
  export FLOWSTEER_APT_CANNED=$data/deb-cache FLOWSTEER_CACHE_DIR=$work/cache
  source "$here/deb_cache.sh"
  pkg=flowsteer-fake version=1:1.0-1
  name='flowsteer-fake_1%3a1.0-1_all.deb'
  cached=$work/cache/debs/$name
  pool=$FLOWSTEER_APT_CANNED/pool/$name
  sha256=$(apt_cache show $pkg | show_field $pkg $version SHA256)

  deb_verify "$pool" "$sha256" 2> /dev/null || fail "deb_verify refuses the good $pool"
  cp "$pool" "$work/short.deb"
  truncate -s 40 "$work/short.deb"
  deb_verify "$work/short.deb" "$sha256" 2> /dev/null && fail "deb_verify takes a cut-short .deb"

  [[ $(deb_fetch $pkg $version) == "$cached" ]] || fail "deb_fetch did not give $cached"
  cmp -s "$pool" "$cached" || fail "$cached differs from the archive's"
  # Used again without a download: the canned archive's index stays, its pool is gone.
  mkdir "$work/no-pool"
  cp -r "$FLOWSTEER_APT_CANNED/show" "$work/no-pool"
  [[ $(FLOWSTEER_APT_CANNED=$work/no-pool deb_fetch $pkg $version 2>&1) == "$cached" ]] ||
    fail "deb_fetch did not use the cached $cached"

  truncate -s 40 "$cached"
  deb_fetch $pkg $version > /dev/null 2> "$work/stderr" ||
    fail "deb_fetch failed on a cut-short copy"
  grep -qF "fetching $name again" "$work/stderr" ||
    fail "deb_fetch did not say it fetched the cut-short copy again: $(cat "$work/stderr")"
  cmp -s "$pool" "$cached" || fail "deb_fetch left the cut-short $cached"

  # An archive that serves other bytes than its index's SHA256: refused, nothing cached.
  cp -r "$FLOWSTEER_APT_CANNED" "$work/corrupt"
  echo corrupt >> "$work/corrupt/pool/$name"
  rm "$cached"
  FLOWSTEER_APT_CANNED=$work/corrupt deb_fetch $pkg $version > /dev/null 2> "$work/stderr" &&
    fail "deb_fetch took a download whose SHA256 is not the archive's"
  grep -qF "not the archive's $sha256" "$work/stderr" ||
    fail "deb_fetch's error does not name the SHA256: $(cat "$work/stderr")"
  leftover=$(ls -A "$work/cache/debs")
  [[ -z $leftover ]] || fail "deb_fetch left $leftover in the cache after a corrupt download"
  exit "$failures"
) || failures=$((failures + $?))

if [[ $failures -gt 0 ]]; then
  echo "kernel_packages_test: $failures check(s) failed" >&2
  exit 1
fi
echo "kernel_packages_test: all checks passed"

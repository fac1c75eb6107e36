# shellcheck shell=bash
# Sourced by the VM scripts: Debian's archive as apt sees it, and a cache of the .debs fetched
# from it that outlives build folders, so a fresh clone on the same machine downloads nothing.
#
# apt_cache and apt_download stand for apt-cache and apt-get download. With
# FLOWSTEER_APT_CANNED=DIR they read DIR instead, so the tests of what uses them need no network:
# DIR/madison/PKG and DIR/show/PKG hold the outputs of `apt-cache madison PKG` and `apt-cache
# show PKG` (no file: a package apt knows nothing of), DIR/pool/FILE the .debs.
#
# The cache is ${FLOWSTEER_CACHE_DIR:-${XDG_CACHE_HOME:-$HOME/.cache}/flowsteer}/debs/: one file
# per package and version under the name apt-get download gives it (PKG_VERSION_ARCH.deb, a ':'
# in VERSION written %3a), checked against the archive's SHA256 each time it is used.

# The functions below are called in $(...), where bash would otherwise drop set -e.
shopt -s inherit_errexit

# apt_cache madison|show PKG...: one call for several packages (each call of apt-cache reads
# all of apt's lists: about 0.5 s where, as in containers, apt keeps no binary cache of them).
apt_cache() {
  local command=$1 pkg
  shift
  if [[ -n ${FLOWSTEER_APT_CANNED:-} ]]; then
    for pkg in "$@"; do
      # A blank line after each, as apt-cache show ends its stanzas.
      if cat "$FLOWSTEER_APT_CANNED/$command/$pkg" 2> /dev/null; then echo; fi
    done
  else
    # Packages apt knows nothing of are left out, as madison does; show fails when it knows none.
    apt-cache "$command" "$@" 2> /dev/null || true
  fi
}

# show_field PKG VERSION FIELD: from `apt-cache show` output on stdin, the FIELD of PKG's stanza
# of VERSION (empty where there is none).
show_field() {
  awk -v RS= -F '\n' -v pkg="$1" -v version="$2" -v field="$3" '
    {
      value = ""; found = 0
      for (i = 1; i <= NF; i++) {
        if ($i == "Package: " pkg) found++
        if ($i == "Version: " version) found++
        if (index($i, field ": ") == 1) value = substr($i, length(field) + 3)
      }
      # Read to the end (no exit), so that a writer into the pipe is never cut off.
      if (found == 2 && !printed++) print value
    }'
}

# apt_download PKG VERSION FILE: PKG of VERSION into the current directory, where apt-get
# download names it FILE.
apt_download() {
  if [[ -n ${FLOWSTEER_APT_CANNED:-} ]]; then
    cp "$FLOWSTEER_APT_CANNED/pool/$3" .
  else
    # As root apt would fetch as its user _apt, which cannot write here, and fall back to root
    # with a warning: root at once, without the warning.
    apt-get download -q -o APT::Sandbox::User=root "$1=$2" < /dev/null >&2
  fi
}

# The folder of what the VM tests keep between build folders (CMake takes its vm-kernel/ from
# here too).
flowsteer_cache_dir() {
  echo "${FLOWSTEER_CACHE_DIR:-${XDG_CACHE_HOME:-$HOME/.cache}/flowsteer}"
}

deb_cache_dir() {
  echo "$(flowsteer_cache_dir)/debs"
}

# deb_verify FILE SHA256: whether FILE has that SHA256 (the archive's for it); says why not on
# stderr.
deb_verify() {
  local actual
  actual=$(sha256sum < "$1")
  actual=${actual%% *}
  [[ $actual == "$2" ]] && return 0
  echo "deb_cache: $1 has SHA256 $actual, not the archive's $2" >&2
  return 1
}

# deb_fetch PKG VERSION: prints the path of PKG's VERSION in the cache, downloaded first where
# the cache has no good copy (none, or one that fails deb_verify: cut short, corrupt).
deb_fetch() {
  local pkg=$1 version=$2 dir stanza arch sha256 name tmp
  dir=$(deb_cache_dir)
  stanza=$(apt_cache show "$pkg")
  arch=$(show_field "$pkg" "$version" Architecture <<< "$stanza")
  sha256=$(show_field "$pkg" "$version" SHA256 <<< "$stanza")
  if [[ -z $arch || -z $sha256 ]]; then
    echo "deb_cache: apt-cache serves no $pkg of version $version (apt-cache madison $pkg)" >&2
    return 1
  fi
  name=${pkg}_${version//:/%3a}_$arch.deb
  if [[ -f $dir/$name ]]; then
    deb_verify "$dir/$name" "$sha256" && { echo "$dir/$name"; return 0; }
    echo "deb_cache: fetching $name again" >&2
  fi
  mkdir -p "$dir"
  # What runs killed midway left; a day old, so no run is still writing it.
  find "$dir" -maxdepth 1 -name '.partial.*' -mmin +1440 -exec rm -rf {} +
  # Downloaded and checked beside the cache, then renamed into it: no reader sees part of a
  # file, and of two runs fetching the same one at once each renames a whole one.
  tmp=$(mktemp -d "$dir/.partial.XXXXXX")
  if (cd "$tmp" && apt_download "$pkg" "$version" "$name") &&
    deb_verify "$tmp/$name" "$sha256"; then
    mv -f "$tmp/$name" "$dir/$name"
    rm -rf "$tmp"
    echo "$dir/$name"
  else
    rm -rf "$tmp"
    echo "deb_cache: could not fetch $pkg $version into $dir (if apt's lists are older than" \
      "the archive, run apt-get update)" >&2
    return 1
  fi
}

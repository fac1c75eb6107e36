#!/usr/bin/env bash
# Usage: kernel_packages.sh
# Chooses the Debian packages the VM tests take their kernel from, by what the archive serves
# now: it moves every few weeks, and not every package of a kernel moves on the same day.
# A set is a linux-image-amd64 version's image (the package it depends on, of that version),
# linux-headers-RELEASE and linux-headers-ABI-common (the image's ABI, for building vimc),
# linux-kbuild-X.Y (the build's host programs: modpost, fixdep) and linux-source-X.Y of the same
# upstream release (X.Y.Z, the part before the Debian revision). Of each package the image's
# own version where it is served and fits, else the newest served one that fits: of the same
# upstream release, and for -common and kbuild allowed by the headers' Depends. The newest
# linux-image-amd64 version with a whole set wins.
# Prints the set, one "ROLE PACKAGE VERSION" line each for the roles image, headers, common,
# kbuild and source; where no version has a whole set, says what each lacks and fails.
# FLOWSTEER_APT_CANNED=DIR reads apt-cache's outputs from DIR (deb_cache.sh).
set -euo pipefail

here=$(cd "$(dirname "$0")" && pwd)
source "$here/deb_cache.sh"

# Versions, one a line on stdin, newest first in dpkg's order (sort -V differs on '~' and '+').
newest_first() {
  local sorted=() v i
  while read -r v; do
    for ((i = ${#sorted[@]}; i > 0; i--)); do
      dpkg --compare-versions "${sorted[i - 1]}" ge "$v" && break
      sorted[i]=${sorted[i - 1]}
    done
    sorted[i]=$v
  done
  [[ ${#sorted[@]} -eq 0 ]] || printf '%s\n' "${sorted[@]}"
}

# names IMAGE VERSION: the packages of the set around the image package IMAGE of VERSION, in the
# order image, headers, common, kbuild, source.
names() {
  local release=${1#linux-image-} series=${2%-*}
  series=${series%.*}
  echo "$1 linux-headers-$release linux-headers-${release%-*}-common linux-kbuild-$series" \
    "linux-source-$series"
}

# served_versions PKG: the versions of PKG in $madison (what the archive serves: apt-cache
# madison leaves out what is only installed), newest first.
served_versions() {
  awk -F '|' -v pkg="$1" '{ gsub(/ /, "") } $1 == pkg { print $2 }' <<< "$madison" |
    sort -u | newest_first
}

# fitting PKG UPSTREAM CONSTRAINT PREFERRED: the served versions of PKG of release UPSTREAM that
# satisfy CONSTRAINT ("OP VERSION" as in Depends, or empty), PREFERRED first, then newest first.
fitting() {
  local pkg=$1 upstream=$2 constraint=$3 preferred=$4 v others=()
  while read -r v; do
    [[ ${v%-*} == "$upstream" ]] || continue
    # shellcheck disable=SC2086 # "OP VERSION": two arguments
    [[ -z $constraint ]] || dpkg --compare-versions "$v" $constraint || continue
    if [[ $v == "$preferred" ]]; then echo "$v"; else others+=("$v"); fi
  done < <(served_versions "$pkg")
  [[ ${#others[@]} -eq 0 ]] || printf '%s\n' "${others[@]}"
}

# constraint_on DEPENDS PKG: the "OP VERSION" a Depends field puts on PKG (empty if none).
# The awk programs here read to the end (no exit): a writer cut off early would fail the pipe.
constraint_on() {
  tr ',' '\n' <<< "$1" |
    awk -v pkg="$2" '{ gsub(/[()]/, "") } $1 == pkg && NF == 3 && !seen++ { print $2, $3 }'
}

# lacks PKG UPSTREAM CONSTRAINT: what a set lacks, for the message where no set is whole.
lacks() {
  echo "no $1 of $2${3:+ satisfying $3} is served (apt-cache madison $1)"
}

# complete_set IMAGE VERSION: prints the set around the image package IMAGE of VERSION, or sets
# `missing` to what it lacks and fails. -common and kbuild are tried with each fitting headers
# version in turn; what the first lacks is reported.
complete_set() {
  local version=$2 upstream=${2%-*} image headers common kbuild source
  local source_version headers_version depends constraint common_version kbuild_version
  read -r image headers common kbuild source <<< "$(names "$1" "$2")"
  missing=
  # Not grep -q: it stops reading early, and pipefail takes the writer's SIGPIPE for a failure.
  if ! served_versions "$image" | grep -xF "$version" > /dev/null; then
    missing=$(lacks "$image" "$upstream" "= $version")
    return 1
  fi
  source_version=$(fitting "$source" "$upstream" "" "$version")
  [[ -n $source_version ]] || { missing=$(lacks "$source" "$upstream" ""); return 1; }
  for headers_version in $(fitting "$headers" "$upstream" "" "$version"); do
    depends=$(show_field "$headers" "$headers_version" Depends <<< "$headers_show")
    constraint=$(constraint_on "$depends" "$common")
    common_version=$(fitting "$common" "$upstream" "$constraint" "$version")
    if [[ -z $common_version ]]; then
      [[ -n $missing ]] || missing=$(lacks "$common" "$upstream" "$constraint")
      continue
    fi
    constraint=$(constraint_on "$depends" "$kbuild")
    kbuild_version=$(fitting "$kbuild" "$upstream" "$constraint" "$version")
    if [[ -z $kbuild_version ]]; then
      [[ -n $missing ]] || missing=$(lacks "$kbuild" "$upstream" "$constraint")
      continue
    fi
    printf '%s\n' "image $image $version" "headers $headers $headers_version" \
      "common $common ${common_version%%$'\n'*}" "kbuild $kbuild ${kbuild_version%%$'\n'*}" \
      "source $source ${source_version%%$'\n'*}"
    return 0
  done
  [[ -n $missing ]] || missing=$(lacks "$headers" "$upstream" "")
  return 1
}

meta=$(apt_cache show linux-image-amd64)
if [[ -z $meta && -z ${FLOWSTEER_APT_CANNED:-} && $(id -u) -eq 0 ]]; then
  # A machine that never ran apt-get update knows no packages yet.
  apt-get update -qq >&2
  meta=$(apt_cache show linux-image-amd64)
fi
if [[ -z $meta ]]; then
  echo "kernel_packages: apt-cache knows no linux-image-amd64 (run apt-get update)" >&2
  exit 1
fi

# linux-image-amd64's versions, newest first, with the image package each depends on.
versions=() images=() all_names=() headers_names=()
for version in $(awk '/^Version: / { print $2 }' <<< "$meta" | sort -u | newest_first); do
  image=$(show_field linux-image-amd64 "$version" Depends <<< "$meta" | tr ',' '\n' |
    awk '$1 ~ /^linux-image-[0-9]/ && !seen++ { print $1 }')
  [[ -n $image ]] || continue
  versions+=("$version")
  images+=("$image")
  read -ra set_names <<< "$(names "$image" "$version")"
  all_names+=("${set_names[@]}")
  headers_names+=("${set_names[1]}")
done
if [[ ${#versions[@]} -eq 0 ]]; then
  echo "kernel_packages: no version of linux-image-amd64 depends on a linux-image-X.Y.Z-N-FLAVOUR" \
    "package (apt-cache show linux-image-amd64)" >&2
  exit 1
fi
# All that is asked of apt, in two calls.
madison=$(apt_cache madison "${all_names[@]}")
headers_show=$(apt_cache show "${headers_names[@]}")

reasons=()
for i in "${!versions[@]}"; do
  complete_set "${images[i]}" "${versions[i]}" && exit 0
  reasons+=("linux-image-amd64 ${versions[i]} (${images[i]}): $missing")
done
echo "kernel_packages: no version of linux-image-amd64 depends on an image whose headers," \
  "kbuild and source are all served:" >&2
printf '  %s\n' "${reasons[@]}" >&2
echo "(run apt-get update if apt's lists are older than the archive)" >&2
exit 1

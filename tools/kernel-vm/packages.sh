# shellcheck shell=bash
# The kernel test machine's Debian packages: resolved from apt's lists (./resolve), downloaded
# into the machine's cache directory, or, when the archive no longer offers a usable set, the
# newest kernel already cached. Sourced by tools/kernel-vm/setup (after lib.sh), and by
# tests/tools/kernel_fetch_test with apt stood in for. The caller sets here, root, flavour and
# inputs (what makes a cached machine ready), and reads back what these functions set.
# shellcheck disable=SC2154,SC2034

# What setup takes from linux-source; the 140 MB package is deleted once they are extracted.
source_files=(drivers/gpio/gpio-sim.c drivers/gpio/gpiolib.h kernel/irq/irq_sim.c
  drivers/usb/gadget/legacy/raw_gadget.c scripts/extract-vmlinux)

# When apt's lists change, and when ./resolve does, the packages are resolved again.
apt_lists_key() {
  { stat -c '%n %Y' /var/lib/apt/lists/*Packages* 2>/dev/null; cat "$here/resolve"; } |
    sha256sum | cut -c1-16
}

# Sets kabi, kver (the image's version), image_pkg, debs (NAME=VERSION: image, headers, -common,
# kbuild), source_spec and compiler_pkg from ./resolve's answer, which is kept until the key
# changes (it asks apt-cache three times: seconds where apt keeps no package cache). Returns 1
# with the reason in $why.
resolve_kernel() {
  local memo=$root/$flavour/resolved key role name version rest status=0
  key=$(apt_lists_key)
  if [[ $(head -n1 "$memo" 2>/dev/null) != "$key" ]]; then
    "$here/resolve" --flavour "$flavour" >"$memo.out" 2>"$memo.err" || status=$?
    if ((status == 2)); then  # not a question of the archive: python3-apt missing, a bad file
      cat "$memo.err" >&2
      exit 125
    fi
    if ((status)); then
      why="apt's lists offer no usable set of packages for the $flavour kernel"$'\n'"$(sed 's/^/  /' "$memo.err")"
      rm -f "$memo" "$memo.out" "$memo.err"
      return 1
    fi
    { echo "$key" && cat "$memo.out"; } >"$memo"
    rm -f "$memo.out" "$memo.err"
  fi
  kabi="" debs=() source_spec="" compiler_pkg=""
  while read -r role name version rest; do
    case $role in
      kernel) kabi=$name kver=$version ;;
      image) image_pkg=$name && debs+=("$name=$version") ;;
      headers | common | kbuild) debs+=("$name=$version") ;;
      source) source_spec=$name=$version ;;
      compiler) compiler_pkg=$name ;;
      note) say "$name $version $rest" ;;
    esac
  done < <(tail -n +2 "$memo")
  [[ -n $kabi && -n $source_spec && ${#debs[@]} == 4 ]] ||
    { rm -f "$memo"; die "resolve gave no complete set ($memo)"; }
}

machine_ready() { [[ $(cat "$dir/ready" 2>/dev/null) == "$inputs" ]]; }
source_extracted() { [[ $(cat "$dir/src/.files" 2>/dev/null) == "${source_files[*]}" ]]; }

# apt-get download, into $dir/debs, of each package of the set not there at its version (the
# source only while its files are not extracted). Other versions of those packages are
# replaced only once every download succeeded. Returns 1 with apt-get's words in $why.
fetch_set() {
  local specs=() spec version wanted=("${debs[@]}")
  source_extracted || wanted+=("$source_spec")
  for spec in "${wanted[@]}"; do
    # apt-get download writes NAME_VERSION_ARCH.deb, with an epoch's colon as %3a.
    version=${spec#*=}
    compgen -G "$dir/debs/${spec%%=*}_${version//:/%3a}_*.deb" >/dev/null || specs+=("$spec")
  done
  ((${#specs[@]})) || return 0
  say "downloading ${specs[*]}"
  rm -rf "$dir/download" && mkdir -p "$dir/download" "$dir/debs"
  if ! (cd "$dir/download" && apt-get download -q "${specs[@]}") >"$dir/apt.log" 2>&1; then
    why="apt-get download ${specs[*]} failed"$'\n'"$(sed 's/^/  /' "$dir/apt.log")"
    rm -rf "$dir/download"
    return 1
  fi
  for spec in "${specs[@]}"; do rm -f "$dir/debs/${spec%%=*}_"*.deb; done
  mv "$dir/download"/*.deb "$dir/debs/"
  rm -rf "$dir/download" "$dir/root/.extracted"  # extracted from other .debs
}

# A cached machine that can be made again without the archive: the source's files extracted
# and the image's .deb kept.
usable_cache() {
  [[ -f $1/src/.files ]] && compgen -G "$1/debs/linux-image-*.deb" >/dev/null
}

# The newest cached kernel of this flavour (by the image's version, as dpkg orders them),
# whatever its age; the names are <kernel>_<image version>, as they always were. Else the
# reason, and the machine cannot be made.
use_cached_kernel() {
  local d best=""
  for d in "$root/$flavour"/*_*/; do
    d=${d%/}
    usable_cache "$d" || continue
    if [[ -z $best ]] || dpkg --compare-versions "${d##*_}" gt "${best##*_}"; then best=$d; fi
  done
  [[ -n $best ]] ||
    die "$why"$'\n'"kernel-vm: and no kernel of flavour $flavour is cached in $root/$flavour"
  say "using the cached $(basename "$best") instead"
  dir=$best kabi=$(basename "$best" | cut -d_ -f1) kver=${best##*_}
  image_pkg=linux-image-$kabi
  compiler_pkg=$(awk '$1 == "compiler" { print $2 }' "$best/packages" 2>/dev/null || true)
  source_spec=""
}

# Sets dir, kabi, kver, image_pkg and the rest for the machine to make, with the set's .debs in
# $dir/debs unless $dir is ready already. A set that cannot be resolved or downloaded may be
# apt's lists lagging the archive, which drops superseded versions: as root the lists are
# refreshed once (apt-get update) and the set resolved again. Then the newest cached kernel;
# then the reason, naming each package.
acquire_kernel() {
  local attempt
  for attempt in 1 2; do
    if resolve_kernel; then
      dir=$root/$flavour/${kabi}_$kver
      machine_ready && return 0
      mkdir -p "$dir"
      if fetch_set; then
        # What the machine is made from, for whoever wonders.
        tail -n +2 "$root/$flavour/resolved" | grep -v '^note ' >"$dir/packages"
        return 0
      fi
      # A directory this attempt made and could not fill is of no use to anyone.
      usable_cache "$dir" || rm -rf "$dir"
    fi
    if ((attempt == 2)) || [[ $(id -u) != 0 ]]; then break; fi
    say "refreshing apt's lists (apt-get update): ${why%%$'\n'*}"
    if ! apt-get update -q >"$root/$flavour/update.log" 2>&1; then
      why+=$'\n'"apt-get update failed"$'\n'"$(sed 's/^/  /' "$root/$flavour/update.log")"
      break
    fi
  done
  dir=""
  use_cached_kernel
}

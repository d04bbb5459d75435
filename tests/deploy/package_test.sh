#!/usr/bin/env bash
# The Debian package (deploy/CMakeLists.txt, docs/deploy.md), in three ctest steps:
#   package_test.sh build BUILD_DIR CPACK      cpack -G DEB makes BUILD_DIR/package/stac_*.deb
#   package_test.sh contents BUILD_DIR         what dpkg-deb shows: files, Depends, conffiles
#   package_test.sh install BUILD_DIR          dpkg -i into a copy-on-write overlay of this
#       machine (a private mount namespace: nothing reaches the real system), then stac --version,
#       stac-node --check of the installed /etc/stac (vehicle.xml's eth1 refused where there is
#       none; complete with loopback.xml), systemd-analyze verify of the unit, an
#       upgrade that keeps the user's edit of a conffile, and a purge that leaves nothing: every
#       file the overlay holds afterwards is dpkg's own bookkeeping. Needs root and overlayfs;
#       skipped (77) without them.
set -euo pipefail
step=$1
build=$(cd "$2" && pwd)
fail() { echo "package_test: FAIL: $*" >&2; exit 1; }
debs=("$build"/package/stac_*_amd64.deb)

case $step in
build)
  rm -rf "$build/package"
  (cd "$build" && "$3" -G DEB --config CPackConfig.cmake > "$build/cpack.log" 2>&1) ||
    { cat "$build/cpack.log" >&2; fail "cpack -G DEB failed (log above)"; }
  debs=("$build"/package/stac_*_amd64.deb)
  [[ -f ${debs[0]} ]] || fail "cpack made no stac_*_amd64.deb in $build/package"
  echo "package_test: built ${debs[0]##*/}"
  ;;

contents)
  deb=${debs[0]}
  [[ -f $deb ]] || fail "no package in $build/package (the build step makes it)"
  mapfile -t files < <(dpkg-deb -c "$deb" | awk '$1 !~ /^d/ {print substr($6, 2)}' | sort)
  expected=(/usr/bin/stac /usr/bin/stac-node /etc/stac/stac.yaml /etc/stac/can/vehicle.dbc
    /etc/stac/dds/vehicle.xml /etc/stac/dds/loopback.xml /lib/systemd/system/stac.service
    /lib/udev/rules.d/60-stac-gs-usb.rules /lib/udev/rules.d/60-stac-cpu-latency.rules
    /lib/systemd/system-generators/stac-cpu-affinity
    /usr/share/stac/models/stac_default.stacmodel
    /usr/share/stac/calib/rosdrivers_64e_s2.1-sztaki.yaml /usr/share/doc/stac/deploy.md
    /usr/share/doc/stac/LICENSE /usr/share/doc/stac/THIRD-PARTY-NOTICES.md)
  for f in "${expected[@]}"; do
    printf '%s\n' "${files[@]}" | grep -qx "$f" || fail "$f is not in the package"
  done
  # Only the two executables: no test, benchmark, example or fuzz program.
  bins=$(printf '%s\n' "${files[@]}" | grep '/bin/' | tr '\n' ' ')
  [[ $bins == "/usr/bin/stac /usr/bin/stac-node " ]] || fail "executables in the package: $bins"
  # Every file under /etc is a conffile, and only those.
  want=$(printf '%s\n' "${files[@]}" | grep '^/etc/' | sort)
  got=$(dpkg-deb --ctrl-tarfile "$deb" | tar -xO ./conffiles | sort)
  [[ $want == "$got" ]] || fail "conffiles differ from the files under /etc:"$'\n'"$got"$'\n'"vs"$'\n'"$want"
  # Depends from dpkg-shlibdeps: Cyclone DDS, yaml-cpp, libpcap... and adduser for postinst.
  depends=$(dpkg-deb -f "$deb" Depends)
  for d in adduser libddsc0debian libyaml-cpp libpcap libtinyxml2 libusb-1.0 libstdc++6; do
    [[ $depends == *"$d"* ]] || fail "Depends has no $d: $depends"
  done
  # The shipped config points into the package, not into a source tree.
  config=$(dpkg-deb --fsys-tarfile "$deb" | tar -xO ./etc/stac/stac.yaml)
  grep -q 'calibration: /usr/share/stac/calib/' <<< "$config" || fail "stac.yaml: calibration"
  grep -q 'model: /usr/share/stac/models/stac_default.stacmodel' <<< "$config" || fail "stac.yaml: model"
  grep -q 'config_file: dds/vehicle.xml' <<< "$config" || fail "stac.yaml: dds.config_file"
  if grep -q 'shared/data\|/work/' <<< "$config"; then fail "stac.yaml names a build machine path"; fi
  echo "package_test: ${#files[@]} files, ${#expected[@]} expected ones present, conffiles and Depends right"
  ;;

install)
  deb=${debs[0]}
  [[ -f $deb ]] || fail "no package in $build/package (the build step makes it)"
  if [[ $(id -u) -ne 0 ]]; then echo "package_test: skipped: installing needs root"; exit 77; fi
  work=$(mktemp -d /tmp/stac-package-test.XXXXXX)
  trap 'rm -rf "$work"' EXIT
  mkdir -p "$work"/{upper,work,root}
  if ! unshare -m --propagation private sh -c \
    "mount -t overlay overlay -o lowerdir=/,upperdir=$work/upper,workdir=$work/work $work/root" 2>/dev/null; then
    echo "package_test: skipped: no overlayfs in a private mount namespace here"
    exit 77
  fi
  # The upgrade: the same files as version <version>+1 (dpkg-deb -R, a new Version, -b).
  mkdir -p "$work/repack"
  dpkg-deb -R "$deb" "$work/repack/stac"
  version=$(dpkg-deb -f "$deb" Version)
  sed -i "s/^Version: .*/Version: ${version}+1/" "$work/repack/stac/DEBIAN/control"
  dpkg-deb -b "$work/repack/stac" "$work/stac-upgrade.deb" > /dev/null
  cp "$deb" "$work/stac.deb"
  cat > "$work/inside.sh" <<'SCRIPT'
set -euo pipefail
fail() { echo "package_test: FAIL: $*" >&2; exit 1; }
dpkg -i /stac.deb > /tmp/dpkg-install.log 2>&1 || { cat /tmp/dpkg-install.log >&2; fail "dpkg -i"; }
[[ $(dpkg-query -W -f='${Status}' stac) == "install ok installed" ]] || fail "not installed"
entry=$(getent passwd stac) || fail "postinst made no user stac"
[[ $entry == *:/usr/sbin/nologin ]] || fail "user stac: $entry"
getent group stac > /dev/null || fail "postinst made no group stac"
v=$(stac --version); [[ $v == "stac ${VERSION} (git "* ]] || fail "stac --version: $v"
v=$(stac-node --version); [[ $v == "stac-node ${VERSION} (git "* ]] || fail "stac-node --version: $v"
# The installed binaries read /etc/stac/stac.yaml by default. Its dds/vehicle.xml names the
# vehicle's port (eth1, to be edited): --check makes the DDS domain as the start does and refuses
# it where there is no such interface. Each check runs in a network namespace of its own (only
# loopback), so nothing Cyclone opens reaches a network.
check=$(unshare -n sh -c 'ip link set lo up && stac-node --check' 2>&1) &&
  fail "stac-node --check accepted an interface the namespace does not have: $check"
[[ $check == *"eth1: does not match an available interface"* &&
   $check == *"/etc/stac/stac.yaml: 'dds.config_file': DDS domain 0: "* ]] ||
  fail "stac-node --check: $check"
echo "package_test: stac-node --check refuses eth1 where there is none"
# With the loopback XML instead, everything the installed configuration names is there.
sed 's|^  config_file: dds/vehicle.xml |  config_file: /etc/stac/dds/loopback.xml|' \
  /etc/stac/stac.yaml > /tmp/stac-loopback.yaml
check=$(unshare -n sh -c 'ip link set lo up && stac-node --check --config /tmp/stac-loopback.yaml' 2>&1) ||
  fail "stac-node --check: $check"
[[ $check == *"/tmp/stac-loopback.yaml is complete: calibration /usr/share/stac/calib/"* ]] ||
  fail "stac-node --check: $check"
echo "package_test: $check"
if command -v systemd-analyze > /dev/null; then
  out=$(systemd-analyze verify /lib/systemd/system/stac.service 2>&1) || fail "systemd-analyze: $out"
  [[ -z $out ]] || fail "systemd-analyze verify: $out"
  echo "package_test: systemd-analyze verify accepts the installed unit"
fi
# The generator gives the service the CPUs the config pins its threads to.
sed -i 's/^  perception_cpu: -1/  perception_cpu: 1/' /etc/stac/stac.yaml
/lib/systemd/system-generators/stac-cpu-affinity /run/systemd/generator /run/systemd/generator.early /run/systemd/generator.late
grep -qx 'CPUAffinity=1' /run/systemd/generator/stac.service.d/50-cpu-affinity.conf ||
  fail "the installed generator wrote no CPUAffinity=1"
sed -i 's/^  perception_cpu: 1/  perception_cpu: -1/' /etc/stac/stac.yaml
rm -r /run/systemd/generator/stac.service.d
# An upgrade keeps a user's edit of a conffile (and asks nothing, leaves no .dpkg-* file).
sed -i 's/^  domain_id: 0 /  domain_id: 7 /' /etc/stac/stac.yaml
grep -q '^  domain_id: 7 ' /etc/stac/stac.yaml || fail "the test's edit did not apply"
dpkg -i /stac-upgrade.deb > /tmp/dpkg-upgrade.log 2>&1 < /dev/null ||
  { cat /tmp/dpkg-upgrade.log >&2; fail "dpkg -i of the upgrade"; }
[[ $(dpkg-query -W -f='${Version}' stac) == "${VERSION}+1" ]] || fail "not upgraded"
grep -q '^  domain_id: 7 ' /etc/stac/stac.yaml || fail "the upgrade lost the user's edit"
if compgen -G '/etc/stac/*.dpkg-*' > /dev/null; then fail "the upgrade left $(ls /etc/stac/*.dpkg-*)"; fi
dpkg --purge stac > /tmp/dpkg-purge.log 2>&1 || { cat /tmp/dpkg-purge.log >&2; fail "dpkg --purge"; }
if getent passwd stac > /dev/null || getent group stac > /dev/null; then fail "purge left user/group stac"; fi
for p in /etc/stac /usr/share/stac /usr/share/doc/stac /usr/bin/stac /usr/bin/stac-node \
         /lib/systemd/system/stac.service /lib/udev/rules.d/60-stac-gs-usb.rules; do
  [[ ! -e $p ]] || fail "purge left $p"
done
SCRIPT
  VERSION=$version unshare -m --propagation private bash -c "
    set -e
    mount -t overlay overlay -o lowerdir=/,upperdir=$work/upper,workdir=$work/work $work/root
    for d in proc sys dev; do mount --rbind /\$d $work/root/\$d; done
    cp $work/stac.deb $work/root/stac.deb && cp $work/stac-upgrade.deb $work/root/stac-upgrade.deb
    chroot $work/root bash $work/inside.sh
    rm $work/root/stac.deb $work/root/stac-upgrade.deb
  " || fail "the install, upgrade and purge (above)"
  # What is left in the overlay is what the whole round trip changed on the machine: only /run (a
  # tmpfs on a real machine: adduser's and systemd-analyze's traces), dpkg's
  # and the shells' bookkeeping (the password files' lock and backups), and /etc/passwd, group,
  # shadow, gshadow, subuid and subgid as they were.
  left=$(cd "$work/upper" && find . \( -type f -o -type l \) | sed 's|^\./|/|' |
    grep -v -E '^/(var/lib/dpkg|var/log|var/cache|tmp|root|run)/' |
    grep -v -E '^/etc/((passwd|group|shadow|gshadow|subuid|subgid)-|\.pwd\.lock)$' | sort || true)
  for f in $left; do
    case $f in
      /etc/passwd | /etc/group | /etc/shadow | /etc/gshadow | /etc/subuid | /etc/subgid)
        cmp -s "$work/upper$f" "$f" || fail "after the purge $f differs from the machine's" ;;
      *) fail "after the purge $f is left" ;;
    esac
  done
  echo "package_test: installed, upgraded keeping the user's edit, purged leaving nothing"
  ;;
*) fail "unknown step $step" ;;
esac

#!/bin/bash
# Boots a throw-away QEMU VM with a real Debian kernel (SocketCAN vcan/can-raw/can-gw/
# can-j1939 and gpio-sim) and runs one guest script in it, with the host's root filesystem
# as the VM's root (read-only 9p + tmpfs overlay): the binaries built on the host run
# unchanged inside. The approach is the team's reference testbed
# (shared/reference/vm-testbed/run-in-vm.sh); see tests/kernel/README.md.
#
#   run-vm.sh GUEST_SCRIPT [KEY=VALUE]...
#
# GUEST_SCRIPT runs in the VM as root under bash with the caller's working directory,
# its first argument the shared output folder; the KEY=VALUE pairs are written to
# OUTPUT/guest.env (shell-quoted) for it to source.
#
# Environment: OPENVCU_VM_CACHE (default /var/cache/openvcu-vm: kernel, headers, gpio-sim.ko;
# outside the source tree so every clone reuses it), VM_TIMEOUT (seconds, default 170),
# VM_MEM (default 1024M), VM_SMP (default 2).
#
# Exit: the guest script's status; 77 when the VM cannot run here (no QEMU, not root, no
# kernel and no mirror to fetch it from): ctest counts that as skipped, never as passed;
# 99 when the VM died without a result, 124 when it ran out of time.
set -euo pipefail

SKIP=77
T0=$(date +%s%N)
log() { printf '[run-vm %5.1fs] %s\n' "$(( ($(date +%s%N) - T0) / 1000000 ))e-3" "$*"; }
skip() { echo "run-vm: SKIPPED: $*" >&2; exit "$SKIP"; }

[[ $# -ge 1 ]] || { echo "usage: run-vm.sh GUEST_SCRIPT [KEY=VALUE]..." >&2; exit 2; }
GUEST_SCRIPT=$(readlink -f "$1"); shift
CACHE=${OPENVCU_VM_CACHE:-/var/cache/openvcu-vm}
VM_TIMEOUT=${VM_TIMEOUT:-170}; VM_MEM=${VM_MEM:-1024M}; VM_SMP=${VM_SMP:-2}
CWD=$PWD

# ---------------------------------------------------------------- can QEMU run here at all?
# 9p with security_model=none and apt-get need root; TCG (software emulation) needs only
# the binary and its firmware. KVM is not used: on these machines /dev/kvm is a nested
# software hypervisor that is ~100x slower than TCG and fails on a stock kernel.
[[ "$(id -u)" == 0 ]] || skip "needs root (9p share of / and the kernel download)"
command -v qemu-system-x86_64 >/dev/null || skip "qemu-system-x86_64 not installed (scripts/install-deps.sh)"
[[ -f /usr/share/qemu/qboot.rom ]] || skip "/usr/share/qemu/qboot.rom missing (qemu-system-x86)"
for tool in busybox cpio modprobe depmod xz make gcc-12 candump ip; do
  command -v "$tool" >/dev/null || [[ -x /bin/$tool ]] || skip "$tool not installed (scripts/install-deps.sh)"
done
# the kernel command line carries the paths: no spaces (the KEY=VALUE pairs go through a file)
[[ "$CWD$GUEST_SCRIPT" != *' '* ]] || { echo "run-vm: the paths must not contain spaces" >&2; exit 2; }

# ---------------------------------------------------------------- kernel + gpio-sim (cached)
mkdir -p "$CACHE"
exec {lockfd}>"$CACHE/.lock"
flock "$lockfd"  # one preparation at a time; a parallel run waits, then reuses it

# linux-image-amd64 is a metapackage: resolve the real ABI (e.g. 6.1.0-41-amd64) once.
if [[ ! -s "$CACHE/kernel.env" ]]; then
  log "resolving the Debian kernel (apt-get update)"
  # stale lists give 404s: the security archive keeps only the newest kernel ABI
  apt-get -o DPkg::Lock::Timeout=600 update -qq || skip "apt-get update failed (no mirror reachable?)"
  ABI=$(apt-cache depends linux-image-amd64 | awk '/Depends: linux-image-/{sub("linux-image-","",$2); print $2; exit}')
  [[ -n "$ABI" ]] || skip "no linux-image-amd64 in the package lists"
  KVER=$(apt-cache show "linux-image-$ABI" | awk '/^Version:/{print $2; exit}')
  SER=$(echo "$ABI" | cut -d. -f1,2)
  echo "ABI=$ABI KVER=$KVER SER=$SER" > "$CACHE/kernel.env.tmp"
  mv "$CACHE/kernel.env.tmp" "$CACHE/kernel.env"
fi
# shellcheck disable=SC1091
. "$CACHE/kernel.env"
KROOT=$CACHE/kroot; HROOT=$CACHE/hroot
if [[ ! -f "$CACHE/kernel.done" ]]; then
  log "downloading kernel $ABI ($KVER) + headers + source (once)"
  rm -rf "$CACHE/debs" "$KROOT" "$HROOT" && mkdir -p "$CACHE/debs"
  # Sandbox::User=root: apt's _apt user cannot write into a root-owned folder
  (cd "$CACHE/debs" && apt-get -q -o APT::Sandbox::User=root download "linux-image-$ABI=$KVER" \
      "linux-headers-$ABI=$KVER" "linux-headers-${ABI%-amd64}-common=$KVER" \
      "linux-kbuild-$SER=$KVER" "linux-source-$SER=$KVER") \
    || skip "kernel download failed (no mirror reachable?); delete $CACHE/kernel.env if the lists were stale"
  dpkg -x "$CACHE"/debs/linux-image-"$ABI"_*.deb "$KROOT"   # unpacked only, never installed
  depmod -b "$KROOT" "$ABI"                                 # the .deb ships no modules.dep
  for deb in "$CACHE"/debs/linux-headers-*.deb "$CACHE"/debs/linux-kbuild-*.deb; do dpkg -x "$deb" "$HROOT"; done
  # the arch headers Makefile includes an absolute /usr/src/... path: point it at $HROOT
  sed -i "s#/usr/src/#$HROOT/usr/src/#" "$HROOT/usr/src/linux-headers-$ABI/Makefile"
  # QEMU boots the ELF vmlinux through its PVH entry point: decompressing the XZ bzImage
  # here saves the guest ~3 s of emulated decompression on every boot.
  off=$(LC_ALL=C grep -obUa $'\xfd7zXZ' "$KROOT/boot/vmlinuz-$ABI" | head -1 | cut -d: -f1)
  xz -dc --single-stream < <(tail -c +$((off + 1)) "$KROOT/boot/vmlinuz-$ABI") > "$CACHE/vmlinux"
  touch "$CACHE/kernel.done"
  log "kernel unpacked"
fi
# Debian's kernels have CONFIG_GPIO_SIM and CONFIG_IRQ_SIM unset: build gpio-sim out of
# tree from exactly this kernel's source, with kernel/irq/irq_sim.c linked in privately.
GS=$CACHE/gpio-sim
if [[ ! -f "$GS/gpio-sim.ko" ]]; then
  log "building gpio-sim.ko (once)"
  rm -rf "$GS" && mkdir -p "$GS/src"
  dpkg-deb --fsys-tarfile "$CACHE"/debs/linux-source-"$SER"_*.deb \
    | tar -xO "./usr/src/linux-source-$SER.tar.xz" | xz -dc \
    | tar -x -C "$GS/src" --strip-components=1 "linux-source-$SER/drivers/gpio/gpio-sim.c" \
        "linux-source-$SER/drivers/gpio/gpiolib.h" "linux-source-$SER/kernel/irq/irq_sim.c"
  cp "$GS/src/drivers/gpio/gpio-sim.c" "$GS/gpio-sim-main.c"
  cp "$GS/src/drivers/gpio/gpiolib.h" "$GS/src/kernel/irq/irq_sim.c" "$GS/"
  sed -i 's/^EXPORT_SYMBOL_GPL(.*);//' "$GS/irq_sim.c"    # private copy: export nothing
  # irq_to_desc() is not exported to modules; generic_handle_irq() does the same thing
  sed -i 's/handle_simple_irq(irq_to_desc(\(.*\)));/generic_handle_irq(\1);/' "$GS/irq_sim.c"
  printf 'obj-m := gpio-sim.o\ngpio-sim-y := gpio-sim-main.o irq_sim.o\n' > "$GS/Makefile"
  nice make -s -C "$HROOT/usr/src/linux-headers-$ABI" M="$GS" modules 2>&1 | { grep -v 'Skipping BTF' || true; }
  [[ -f "$GS/gpio-sim.ko" ]] || { echo "run-vm: gpio-sim build failed" >&2; exit 98; }
  strip --strip-debug "$GS/gpio-sim.ko"
  log "gpio-sim.ko built"
fi
flock -u "$lockfd"

# ---------------------------------------------------------------- output share + initramfs
# The output folder is shared read-write into the VM at the same path. It lives under the
# caller's folder (the build tree), not /tmp, so the guest may put a tmpfs on /tmp.
VMOUT=$CWD/vm-out   # the last run's logs stay for inspection until the next run
rm -rf "$VMOUT" && mkdir -p "$VMOUT"
for kv in "$@"; do printf '%s=%q\n' "${kv%%=*}" "${kv#*=}"; done > "$VMOUT/guest.env"
IRD=$VMOUT/initrd
mkdir -p "$IRD"/{bin,proc,sys,dev,mods,hostro,rw,newroot}
cp /bin/busybox "$IRD/bin/"
for m in vcan can-raw can-bcm can-gw can-j1939 virtio_pci 9pnet_virtio 9p overlay configfs; do
  modprobe -d "$KROOT" -S "$ABI" --show-depends "$m" | awk '$1=="insmod"{print $2}'
done | awk '!seen[$0]++' | while read -r ko; do
  cp "$ko" "$IRD/mods/"; basename "$ko" .ko >> "$IRD/mods/order"
done
cp "$GS/gpio-sim.ko" "$IRD/mods/"; echo gpio-sim >> "$IRD/mods/order"
# softdog is not loaded at boot: a guest script loads it (after the watchdog core it needs,
# listed in load order in softdog/order) with its own parameters
mkdir -p "$VMOUT/softdog"
modprobe -d "$KROOT" -S "$ABI" --show-depends softdog | awk '$1=="insmod"{print $2}' | while read -r ko; do
  cp "$ko" "$VMOUT/softdog/"; basename "$ko" .ko >> "$VMOUT/softdog/order"
done
# /init: load the modules, overlay the host root, chroot and run the guest script.
# Unknown key=value pairs of the kernel command line arrive as its environment.
cat > "$IRD/init" <<'EOF'
#!/bin/busybox sh
/bin/busybox --install -s /bin
export PATH=/bin
mount -t proc proc /proc; mount -t sysfs sys /sys; mount -t devtmpfs dev /dev
for m in $(cat /mods/order); do insmod /mods/$m.ko || echo "VM insmod FAILED: $m"; done
mount -t 9p -o trans=virtio,version=9p2000.L,ro,msize=512000,cache=loose hostroot /hostro
mount -t tmpfs -o size=75% tmpfs /rw && mkdir -p /rw/upper /rw/work
mount -t overlay overlay -o lowerdir=/hostro,upperdir=/rw/upper,workdir=/rw/work /newroot
R=/newroot
mount -t proc proc $R/proc; mount -t sysfs sys $R/sys; mount -t devtmpfs dev $R/dev
mkdir -p $R/dev/pts $R/dev/shm; mount -t devpts devpts $R/dev/pts; mount -t tmpfs tmpfs $R/dev/shm
mount -t configfs configfs $R/sys/kernel/config
mount -t tmpfs tmpfs $R/run; mount -t tmpfs tmpfs $R/tmp
for d in $(echo "$vmkeep" | tr ',' ' '); do mkdir -p $R$d && mount -o bind /hostro$d $R$d; done
mkdir -p $R$vmout && mount -t 9p -o trans=virtio,version=9p2000.L,msize=512000 vmout $R$vmout
# the overlay's layers, read-only, for a guest that checks what it changed in the root
# (guest-install.sh): lower = the host's root, upper = every write of the VM (whiteouts = deletions)
mkdir -p $R/run/vm-root/lower $R/run/vm-root/upper
mount -o bind /hostro $R/run/vm-root/lower
mount -o bind /rw/upper $R/run/vm-root/upper && mount -o remount,bind,ro $R/run/vm-root/upper
ip link set lo up
echo "VM $(cut -d' ' -f1 /proc/uptime) s: kernel up, running the guest script"
chroot $R /bin/sh -c "cd '$vmcwd' && exec /bin/bash '$vmtest' '$vmout'" </dev/null
rc=$?
echo $rc > $R$vmout/exit_code
sync; umount $R$vmout 2>/dev/null
poweroff -f
EOF
chmod +x "$IRD/init"
(cd "$IRD" && find . | cpio -o -H newc --quiet | gzip -1) > "$VMOUT/initrd.gz"
rm -rf "$IRD"

# The guest puts a fresh tmpfs on /tmp (iceoryx's /tmp/roudi stays private), which would
# hide a tree that lives under /tmp (a clone in /tmp/fresh, say): the top folders under
# /tmp of the script, this folder and every path argument are bound back in, read-only.
# (an if, not '[[ ]] && ...': under pipefail a last path outside /tmp would fail the loop)
KEEP=$(for p in "$GUEST_SCRIPT" "$CWD" "${@#*=}"; do
  if [[ $p == /tmp/?* ]]; then rest=${p#/tmp/}; echo "/tmp/${rest%%/*}"; fi
done | sort -u | paste -sd, -)

# ---------------------------------------------------------------- boot + run
# the host's load decides how steadily the emulated CPUs run (can-tx's period check)
log "booting $ABI (TCG, $VM_SMP vCPU, $VM_MEM, no network device); host load $(cut -d' ' -f1-3 /proc/loadavg)"
# The VM runs in the background so that a SIGTERM/SIGINT (ctest's timeout, Ctrl-C) reaches
# the trap at once, which ends QEMU by its pid file: nothing is left behind.
trap 'rm -rf "$VMOUT/initrd"; [[ -s $VMOUT/qemu.pid ]] && kill "$(cat "$VMOUT/qemu.pid")" 2>/dev/null' EXIT
trap 'exit 143' TERM INT
{ timeout -k 5 "$VM_TIMEOUT" qemu-system-x86_64 -accel tcg -smp "$VM_SMP" -m "$VM_MEM" \
    -nographic -no-reboot -nic none -vga none -bios /usr/share/qemu/qboot.rom -pidfile "$VMOUT/qemu.pid" \
    -kernel "$CACHE/vmlinux" -initrd "$VMOUT/initrd.gz" \
    -append "console=ttyS0 quiet panic=-1 vmtest=$GUEST_SCRIPT vmcwd=$CWD vmout=$VMOUT vmkeep=$KEEP" \
    -virtfs local,path=/,mount_tag=hostroot,security_model=none,readonly=on,multidevs=remap \
    -virtfs local,path="$VMOUT",mount_tag=vmout,security_model=none \
    </dev/null; echo $? > "$VMOUT/qemu.status"; } 2>&1 | sed -u 's/\r$//' | tee "$VMOUT/console.log" &
wait $! || true
qrc=$(cat "$VMOUT/qemu.status" 2>/dev/null || echo 99)
rm -f "$VMOUT/qemu.pid"   # QEMU has ended: never kill a reused pid later
if [[ -s "$VMOUT/exit_code" ]]; then
  rc=$(cat "$VMOUT/exit_code")
elif [[ $qrc == 124 || $qrc == 137 ]]; then
  rc=124; echo "run-vm: FAILED: the VM did not finish within ${VM_TIMEOUT} s" >&2
else
  rc=99; echo "run-vm: FAILED: the VM ended without a result (qemu status $qrc)" >&2
fi
log "VM finished, guest status $rc; console log and outputs in $VMOUT"
exit "$rc"

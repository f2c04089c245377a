# shellcheck shell=bash
# Shared by tools/kernel-vm/setup and tools/kernel-vm/run (sourced, not run).

# The cache lives outside the repository: a fresh clone, `git clean` and other checkouts share
# it, and it is keyed on the kernel's version, which Debian moves with security updates.
vm_cache_root() {
  echo "${HAPTICD_VM_CACHE:-${XDG_CACHE_HOME:-${HOME:-/tmp}/.cache}/hapticd/kernel-vm}"
}

say() { echo "kernel-vm: $*" >&2; }
# 125: the machine could not be made or booted (the command's own status is never 125 here
# unless the command itself returned it).
die() {
  echo "kernel-vm: $*" >&2
  exit 125
}

check_flavour() {
  case $1 in
    amd64 | rt-amd64) ;;
    *) die "unknown flavour '$1' (amd64 or rt-amd64)" ;;
  esac
}

# Sets the array qemu_cmd to boot VMLINUX with INITRAMFS under ACCEL (kvm or tcg), with the
# kernel console on the first serial port written to CONSOLE_LOG. The caller appends shares
# and further serial ports. CLOCK "instructions" (tcg only) makes the guest's clock count the
# instructions it runs, one a nanosecond, and skip its idle time (-icount shift=0,sleep=off):
# a deterministic 1 GHz machine whose timing is its code's, not the loaded host's. icount runs
# every CPU on one host thread (thread=single); qemu 7.2 hangs bringing up a second CPU under
# it, so that guest has one (run --timed).
# -nodefaults drops the VGA card and the NIC (and the iPXE ROM the firmware would run for it).
# quiet: the console is a log, read on failure. panic=-1 with -no-reboot makes a panic end qemu
# at once instead of hanging until the time-out. unknown_nmi_panic and panic_print=0x40: an NMI
# from the monitor (tools/kernel-vm/run, at a time-out) panics with every CPU's backtrace.
qemu_command() {  # ACCEL VMLINUX INITRAMFS CONSOLE_LOG MEMORY_MB CPUS EXTRA_KERNEL_ARGS [CLOCK]
  local accel=$1 vmlinux=$2 initramfs=$3 console=$4 memory=$5 cpus=$6 extra=$7 clock=${8:-host}
  qemu_cmd=(qemu-system-x86_64 -machine pc -nodefaults -no-user-config -display none
    -no-reboot -rtc base=utc -m "$memory" -smp "$cpus"
    -kernel "$vmlinux" -initrd "$initramfs"
    -append "console=ttyS0 quiet loglevel=4 panic=-1 mitigations=off unknown_nmi_panic panic_print=0x40 $extra"
    -chardev "file,id=console,path=$console" -serial chardev:console)
  case $accel in
    kvm) qemu_cmd+=(-accel kvm -cpu host) ;;
    tcg) if [[ $clock == instructions ]]; then
           qemu_cmd+=(-accel tcg,thread=single -cpu max -icount shift=0,sleep=off)
         else
           qemu_cmd+=(-accel tcg,thread=multi -cpu max)
         fi ;;
    *) die "unknown accelerator '$accel' (kvm or tcg)" ;;
  esac
}

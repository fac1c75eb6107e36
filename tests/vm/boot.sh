#!/usr/bin/env bash
# Usage: boot.sh KERNEL_ROOT INITRAMFS LOG [TIMEOUT_S [MEMORY_MB [CPUS]]]
# Boots the kernel unpacked at KERNEL_ROOT with INITRAMFS under qemu, software emulation only
# (-accel tcg: /dev/kvm exists on some machines here but hung; several CPUs are emulated on as
# many host threads), console on the serial port, which is written to LOG. The emulated CPU has
# SSE4.2 but no AVX (Westmere): with -cpu max OpenCV and Mesa chose AVX2 code, which the emulator
# runs several times slower, and the simulation-in-the-loop robot fell 170 ms behind its camera
# (35 ms without). The VM powers off when /init ends; a kernel panic ends qemu too (panic=-1
# reboots, -no-reboot turns that into an exit).
set -euo pipefail

kroot=${1:?usage}; initramfs=${2:?usage}; log=${3:?usage}; timeout_s=${4:-90}; memory_mb=${5:-512}; cpus=${6:-1}
kernel=$(ls "$kroot"/boot/vmlinuz-*)
timeout "$timeout_s" qemu-system-x86_64 -accel tcg,thread=multi -cpu Westmere -m "$memory_mb" -smp "$cpus" \
  -nographic -monitor none -no-reboot \
  -kernel "$kernel" -initrd "$initramfs" \
  -append "console=ttyS0 panic=-1 quiet" > "$log" 2>&1

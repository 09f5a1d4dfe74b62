# Cross toolchain for the NVIDIA Jetson Orin (aarch64, Ubuntu 22.04).
# Needs g++-aarch64-linux-gnu and an aarch64 sysroot with the -dev packages of
# toolchain/install-deps.sh (e.g. a copy of the Jetson's / or a debootstrap of jammy arm64):
#   cmake --preset jetson -DCOMPANION_SYSROOT=/path/to/sysroot
# Building natively on the Jetson needs no toolchain file: use the `release` preset there.
set(CMAKE_SYSTEM_NAME Linux)
set(CMAKE_SYSTEM_PROCESSOR aarch64)
set(CMAKE_C_COMPILER aarch64-linux-gnu-gcc)
set(CMAKE_CXX_COMPILER aarch64-linux-gnu-g++)
if(DEFINED COMPANION_SYSROOT)
  set(CMAKE_SYSROOT "${COMPANION_SYSROOT}")
  set(ENV{PKG_CONFIG_SYSROOT_DIR} "${COMPANION_SYSROOT}")
  set(ENV{PKG_CONFIG_LIBDIR} "${COMPANION_SYSROOT}/usr/lib/aarch64-linux-gnu/pkgconfig:${COMPANION_SYSROOT}/usr/share/pkgconfig")
endif()
set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE ONLY)
# Jetson Orin: Cortex-A78AE.
set(CMAKE_CXX_FLAGS_INIT "-mcpu=cortex-a78ae")

# aarch64 Linux with Debian's cross gcc (gcc-aarch64-linux-gnu).
set(CMAKE_SYSTEM_NAME Linux)
set(CMAKE_SYSTEM_PROCESSOR aarch64)
set(CMAKE_C_COMPILER aarch64-linux-gnu-gcc)
set(STO_FMI2_PLATFORM "")  # FMI 2.0 names no aarch64 folder
set(STO_FMI3_PLATFORM aarch64-linux)

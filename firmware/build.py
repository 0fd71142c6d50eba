#!/usr/bin/env python3
"""Build labkit's Arduino sketches without arduino-cli, and the simavr test harness.

    python3 firmware/build.py firmware/labkit_tach [--out build/firmware]
    python3 firmware/build.py --harness [--out build/firmware]

A sketch is compiled for an Arduino Uno (ATmega328P, 16 MHz) against the Arduino AVR core
of the Debian package ``arduino-core-avr`` (``/usr/share/arduino/hardware/arduino/avr``,
or ``$ARDUINO_AVR_CORE``) with avr-gcc, using the compiler flags of the core's
``platform.txt`` (without LTO). The ``.ino`` is compiled as C++ behind ``#include
<Arduino.h>``; labkit's sketches declare every function before its first use, so no
prototype generation is needed. Output: ``<out>/<sketch>.elf`` and ``<out>/<sketch>.hex``.

``--harness`` compiles ``firmware/sim/labkit_simavr.c`` with gcc against libsimavr
(Debian ``libsimavr-dev``, ``libsimavrparts1``): an ATmega328P running a ``.hex`` with its
UART on a pseudo-terminal, pulse trains on a pin and servo pulse widths measured on another
(see that file). ``firmware/ci/install-toolchain.sh`` installs everything.

Exit status 0 on success; a missing tool or a compiler error prints one line naming it and
exits 2.
"""

from __future__ import annotations

import argparse
import os
import shutil
import subprocess
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
DEFAULT_CORE = Path("/usr/share/arduino/hardware/arduino/avr")
MCU_FLAGS = ["-mmcu=atmega328p", "-DF_CPU=16000000L", "-DARDUINO=10807", "-DARDUINO_AVR_UNO",
             "-DARDUINO_ARCH_AVR"]
C_FLAGS = ["-c", "-g", "-Os", "-w", "-std=gnu11", "-ffunction-sections", "-fdata-sections"]
CPP_FLAGS = ["-c", "-g", "-Os", "-w", "-std=gnu++11", "-fpermissive", "-fno-exceptions",
             "-ffunction-sections", "-fdata-sections", "-fno-threadsafe-statics",
             # avr-gcc 5.4 (Debian 12) defines DECIMAL_DIG for C only; core 1.8.7 uses it in C++
             "-DDECIMAL_DIG=__DECIMAL_DIG__"]
S_FLAGS = ["-c", "-g", "-x", "assembler-with-cpp"]


class BuildError(Exception):
    """A missing tool or a failed compile: one line for the user."""


def arduino_core() -> Path:
    core = Path(os.environ.get("ARDUINO_AVR_CORE", DEFAULT_CORE))
    if not (core / "cores" / "arduino" / "Arduino.h").is_file():
        raise BuildError(f"Arduino AVR core not found at {core} (install arduino-core-avr: "
                         "firmware/ci/install-toolchain.sh, or set ARDUINO_AVR_CORE)")
    return core


def tool(name: str) -> str:
    path = shutil.which(name)
    if path is None:
        raise BuildError(f"{name} not found (install gcc-avr and avr-libc: firmware/ci/install-toolchain.sh)")
    return path


def run(cmd: list[str]) -> None:
    done = subprocess.run(cmd, capture_output=True, text=True, check=False)
    if done.returncode != 0:
        first = (done.stderr or done.stdout).strip().splitlines()
        raise BuildError(f"{Path(cmd[0]).name} failed: {' '.join(first[:6]) or 'no output'}")


def compile_one(source: Path, obj: Path, includes: list[str]) -> Path:
    obj.parent.mkdir(parents=True, exist_ok=True)
    if obj.exists() and obj.stat().st_mtime >= source.stat().st_mtime:
        return obj
    if source.suffix == ".c":
        cmd = [tool("avr-gcc"), *C_FLAGS, *MCU_FLAGS, *includes, str(source), "-o", str(obj)]
    elif source.suffix == ".S":
        cmd = [tool("avr-gcc"), *S_FLAGS, *MCU_FLAGS, *includes, str(source), "-o", str(obj)]
    else:
        cmd = [tool("avr-g++"), *CPP_FLAGS, *MCU_FLAGS, *includes, "-x", "c++", str(source),
               "-o", str(obj)]
    run(cmd)
    return obj


def build_core(core: Path, out: Path, includes: list[str]) -> Path:
    """The Arduino core as ``core.a`` (cached in ``out``)."""
    archive = out / "core" / "core.a"
    if archive.exists():
        return archive
    objects = []
    for source in sorted((core / "cores" / "arduino").iterdir()):
        if source.suffix in (".c", ".cpp", ".S"):
            objects.append(compile_one(source, out / "core" / (source.name + ".o"), includes))
    run([tool("avr-gcc-ar") if shutil.which("avr-gcc-ar") else tool("avr-ar"), "rcs",
         str(archive), *map(str, objects)])
    return archive


def build_sketch(sketch_dir: Path, out: Path) -> Path:
    """Compile ``sketch_dir/<name>.ino`` -> ``out/<name>.hex``; returns the .hex path."""
    sketch_dir = sketch_dir.resolve()
    ino = sketch_dir / f"{sketch_dir.name}.ino"
    if not ino.is_file():
        raise BuildError(f"no sketch {ino}")
    core = arduino_core()
    includes = [f"-I{core / 'cores' / 'arduino'}", f"-I{core / 'variants' / 'standard'}",
                f"-I{sketch_dir}"]
    out.mkdir(parents=True, exist_ok=True)
    archive = build_core(core, out, includes)
    wrapped = out / f"{sketch_dir.name}.ino.cpp"
    wrapped.write_text(f'#include <Arduino.h>\n#line 1 "{ino}"\n' + ino.read_text(encoding="utf-8"),
                       encoding="utf-8")
    obj = compile_one(wrapped, out / f"{sketch_dir.name}.ino.o", includes)
    elf = out / f"{sketch_dir.name}.elf"
    run([tool("avr-gcc"), "-w", "-Os", "-Wl,--gc-sections", "-mmcu=atmega328p", "-o", str(elf),
         str(obj), str(archive), "-lm"])
    hex_file = out / f"{sketch_dir.name}.hex"
    run([tool("avr-objcopy"), "-O", "ihex", "-R", ".eeprom", str(elf), str(hex_file)])
    return hex_file


def build_harness(out: Path) -> Path:
    """gcc firmware/sim/labkit_simavr.c against libsimavr -> ``out/labkit_simavr``."""
    include = Path("/usr/include/simavr")
    if not (include / "sim_avr.h").is_file() or not (include / "parts" / "uart_pty.h").is_file():
        raise BuildError("simavr headers not found (install libsimavr-dev: firmware/ci/install-toolchain.sh)")
    out.mkdir(parents=True, exist_ok=True)
    exe = out / "labkit_simavr"
    source = HERE / "sim" / "labkit_simavr.c"
    run([tool("gcc"), "-O2", "-std=gnu11", "-Wall", f"-I{include}", f"-I{include / 'parts'}",
         str(source), "-o", str(exe), "-lsimavrparts", "-lsimavr", "-lelf", "-lpthread", "-lutil", "-lm"])
    return exe


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("sketch", nargs="?", type=Path, help="sketch directory, e.g. firmware/labkit_tach")
    parser.add_argument("--harness", action="store_true", help="build the simavr harness instead")
    parser.add_argument("--out", type=Path, default=Path("build/firmware"), help="output directory")
    args = parser.parse_args(argv)
    try:
        if args.harness:
            print(build_harness(args.out))
        elif args.sketch is not None:
            print(build_sketch(args.sketch, args.out))
        else:
            parser.error("give a sketch directory or --harness")
    except BuildError as exc:
        print(f"build.py: {exc}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())

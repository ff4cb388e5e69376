"""The build steps pyproject.toml cannot declare: the firmware logic compiled into the wheel as
the package's own shared library, the firmware image and example scenarios copied in as package
data, and the image carried in the sdist.

Everything else (name, version, dependencies, entry point) is in pyproject.toml.
"""

from __future__ import annotations

import hashlib
import os
import re
import shlex
import shutil
import subprocess
from pathlib import Path

from setuptools import Extension, setup
from setuptools.command.bdist_wheel import bdist_wheel
from setuptools.command.build_ext import build_ext
from setuptools.command.build_py import build_py
from setuptools.command.sdist import sdist

LOGIC_SOURCES = sorted(str(p) for p in Path("firmware/lib").glob("*/*.cpp"))
LOGIC_INCLUDES = sorted(str(p) for p in Path("firmware/lib").glob("*") if p.is_dir())
# The same flags as the Makefile's `native` target, so a wheel runs the very code `make native`
# builds and the C++ checks test.
NATIVE_FLAGS = ["-std=gnu++11", "-Wall", "-Wextra", "-Werror", "-Wshadow", "-fPIC", "-O2"]
FIRMWARE_IMAGES = ("particle.hex", "particle.elf")
DEFINITION_HEADER = Path("firmware/lib/protocol/protocol_gen.h")


class BuildNativeLibrary(build_ext):
    """Links firmware/lib into particlebot/firmware/libparticle.so, a plain C library that
    particlebot.firmware.native loads with ctypes (not a Python extension module, so no
    Python.h, no interpreter-specific file name)."""

    def get_ext_filename(self, fullname: str) -> str:
        return os.path.join(*fullname.split(".")[:-1], "libparticle.so")

    def build_extension(self, ext: Extension) -> None:
        # An editable install builds it too (setuptools then copies it beside the sources, where
        # git ignores it), though a clone loads build/native first (`make native`): setuptools
        # fails an editable install whose extension left no file.
        target = Path(self.get_ext_fullpath(ext.name))
        target.parent.mkdir(parents=True, exist_ok=True)
        compiler = shlex.split(os.environ.get("CXX", "c++"))
        includes = [f"-I{d}" for d in ext.include_dirs]
        command = [*compiler, *NATIVE_FLAGS, *includes, "-shared", "-o", str(target), *ext.sources]
        print(" ".join(command))
        subprocess.run(command, check=True)


class CopyPackageData(build_py):
    """Adds what lives outside host/ to the package: the firmware image `make firmware` built
    (with a manifest naming its definition hash) and the example scenarios."""

    def run(self) -> None:
        super().run()
        if self.editable_mode:  # a clone's editable install finds build/ and scenarios/ itself
            return
        data = Path(self.build_lib) / "particlebot" / "_data"
        shutil.rmtree(data, ignore_errors=True)
        shutil.copytree("scenarios", data / "scenarios")
        images = [Path("build/firmware") / name for name in FIRMWARE_IMAGES]
        missing = [str(image) for image in images if not image.is_file()]
        if missing:
            raise SystemExit(
                f"{', '.join(missing)} missing: run `make firmware` before building the wheel"
            )
        firmware = data / "firmware"
        firmware.mkdir(parents=True)
        for image in images:
            shutil.copy2(image, firmware / image.name)
        found = re.search(r"kDefinitionHash = (0x[0-9A-F]{8})", DEFINITION_HEADER.read_text())
        if found is None:
            raise SystemExit(f"no kDefinitionHash in {DEFINITION_HEADER}")
        digest = hashlib.sha256(images[0].read_bytes()).hexdigest()
        (firmware / "particle.toml").write_text(
            "# The firmware image this package carries, and the protocol definition it speaks.\n"
            f'definition_hash = {found.group(1)}\nsha256 = "{digest}"\n',
            encoding="utf-8",
        )


class SourceWithFirmware(sdist):
    """Puts the firmware image `make firmware` built into the sdist (setuptools leaves build/ out
    of it), so that a wheel built from the sdist needs no AVR toolchain."""

    def make_release_tree(self, base_dir: str, files: list[str]) -> None:
        super().make_release_tree(base_dir, files)
        target = Path(base_dir) / "build" / "firmware"
        target.mkdir(parents=True, exist_ok=True)
        for name in FIRMWARE_IMAGES:
            image = Path("build/firmware") / name
            if image.is_file():
                shutil.copy2(image, target / name)


class PlatformWheel(bdist_wheel):
    """Tags the wheel py3-none-<platform>: it holds a C library for one platform but nothing that
    depends on the Python version or its ABI."""

    def get_tag(self) -> tuple[str, str, str]:
        _, _, platform = super().get_tag()
        return "py3", "none", platform


setup(
    ext_modules=[
        Extension(
            "particlebot.firmware.libparticle",
            sources=LOGIC_SOURCES,
            include_dirs=LOGIC_INCLUDES,
        )
    ],
    cmdclass={
        "build_ext": BuildNativeLibrary,
        "build_py": CopyPackageData,
        "sdist": SourceWithFirmware,
        "bdist_wheel": PlatformWheel,
    },
)

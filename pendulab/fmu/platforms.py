"""Target platforms of FMU binaries, their cross compilers, and the symbols a built binary exports.

The host platform is compiled with the host C compiler (as before); any other platform is
cross-compiled with Debian's cross gcc when it is on PATH (``x86_64-w64-mingw32-gcc``,
``aarch64-linux-gnu-gcc``, ...) or else with Zig's C compiler from the ``ziglang`` wheel
(``pip install "pendulab[cross]"``). Every binary is checked after the build: its exported
function names are read from the file itself (ELF ``.dynsym``, PE export table) and must be
exactly the FMI functions of the standard header. What a binary needs from the system's C runtime (the
highest ``GLIBC_x.y`` symbol version of an ELF file, the C runtime DLLs a PE file imports) is read the same
way (:func:`runtime_requirement`) and written into the FMU's documentation. On Linux with Zig installed the
host binary too is built by Zig for glibc 2.17 (:func:`portable_host_compiler`).
"""

from __future__ import annotations

import os
import platform as _platform
import re
import shutil
import struct
import sys
from dataclasses import dataclass
from pathlib import Path

from .._checks import MissingExtraError

__all__ = [
    "Platform",
    "PLATFORMS",
    "GLIBC_BASELINE",
    "host_platform",
    "resolve_platforms",
    "cross_compiler",
    "portable_host_compiler",
    "zig_available",
    "exported_symbols",
    "fmi_functions",
    "glibc_versions",
    "runtime_requirement",
]


@dataclass(frozen=True)
class Platform:
    """One binary target.

    Attributes
    ----------
    name : str
        FMI 3 platform tuple, e.g. ``x86_64-windows``.
    fmi2 : str or None
        FMI 2 folder (``linux64``, ``win64``); None when FMI 2.0 defines none (aarch64).
    suffix : str
        Shared-library suffix.
    zig_target : str
        ``zig cc -target`` value (glibc 2.17 for Linux: loads on every distribution since 2014).
    gcc : tuple of str
        Debian cross compilers that build for it.
    """

    name: str
    fmi2: str | None
    suffix: str
    zig_target: str
    gcc: tuple[str, ...]

    def folder(self, fmi_version: int) -> str:
        """Folder under ``binaries/`` for ``fmi_version``.

        Parameters
        ----------
        fmi_version : {2, 3}
            FMI standard.

        Returns
        -------
        str
            e.g. ``win64`` (FMI 2) or ``x86_64-windows`` (FMI 3).

        Raises
        ------
        ValueError
            FMI 2.0 defines no folder for this platform.
        """
        if fmi_version == 3:
            return self.name
        if self.fmi2 is None:
            raise ValueError(
                f"platforms: FMI 2.0 defines no binaries folder for {self.name!r} (only win32/win64, linux32/linux64, "
                "darwin32/darwin64); export an FMI 3 FMU for it (fmi_version=3, --fmi-version 3)"
            )
        return self.fmi2


PLATFORMS: dict[str, Platform] = {
    "x86_64-linux": Platform("x86_64-linux", "linux64", ".so", "x86_64-linux-gnu.2.17", ("x86_64-linux-gnu-gcc",)),
    "aarch64-linux": Platform("aarch64-linux", None, ".so", "aarch64-linux-gnu.2.17", ("aarch64-linux-gnu-gcc",)),
    "x86_64-windows": Platform("x86_64-windows", "win64", ".dll", "x86_64-windows-gnu", ("x86_64-w64-mingw32-gcc",)),
}
#: FMI 2 folder names and common spellings accepted for the FMI 3 tuples.
_ALIASES = {"linux64": "x86_64-linux", "win64": "x86_64-windows", "arm64-linux": "aarch64-linux"}


def host_platform() -> str:
    """FMI 3 platform tuple of this machine, e.g. ``x86_64-linux``.

    Returns
    -------
    str
        ``<arch>-<system>``.
    """
    system = {"Linux": "linux", "Darwin": "darwin", "Windows": "windows"}.get(_platform.system(), _platform.system().lower())
    machine = _platform.machine().lower()
    return f"{ {'amd64': 'x86_64', 'arm64': 'aarch64'}.get(machine, machine) }-{system}"


def resolve_platforms(platforms, fmi_version: int) -> tuple[Platform, ...]:
    """Validate and normalize the ``platforms`` argument of the export.

    Parameters
    ----------
    platforms : str or sequence of str
        Platform names (FMI 3 tuples or FMI 2 folders), a comma-separated string allowed.
    fmi_version : {2, 3}
        FMI standard (FMI 2.0 has no aarch64 folder).

    Returns
    -------
    tuple of Platform
        Unique, in the given order.

    Raises
    ------
    TypeError
        Not a string or a sequence of strings.
    ValueError
        Empty, unknown platform, or no FMI 2 folder for it.
    """
    if isinstance(platforms, str):
        names = [p.strip() for p in platforms.split(",") if p.strip()]
    elif isinstance(platforms, (list, tuple)) and all(isinstance(p, str) for p in platforms):
        names = [p.strip() for p in platforms]
    else:
        raise TypeError(f"platforms must be a string or a list of strings, got {platforms!r}")
    if not names:
        raise ValueError(f"platforms must name at least one platform, got {platforms!r}")
    out: list[Platform] = []
    for name in names:
        key = _ALIASES.get(name, name)
        if key not in PLATFORMS:
            known = sorted({*PLATFORMS, *_ALIASES})
            raise ValueError(f"platforms: unknown platform {name!r}; expected one of {', '.join(known)}")
        plat = PLATFORMS[key]
        plat.folder(fmi_version)  # raises for FMI 2 without a folder
        if plat not in out:
            out.append(plat)
    return tuple(out)


def cross_compiler(plat: Platform) -> list[str]:
    """Compiler command for ``plat`` (not the host): a Debian cross gcc on PATH, else ``python -m ziglang cc``.

    Parameters
    ----------
    plat : Platform
        Target.

    Returns
    -------
    list of str
        Command and leading arguments.

    Raises
    ------
    MissingExtraError (ImportError)
        Neither a Debian cross compiler nor the ``ziglang`` package is installed.
    """
    for gcc in plat.gcc:
        path = shutil.which(gcc)
        if path:
            return [path]
    try:
        import ziglang  # noqa: F401
    except ImportError as exc:
        raise MissingExtraError(
            f"cross-compiling the FMU for {plat.name} needs Zig's C compiler, which is not installed: "
            f'pip install "pendulab[cross]" (or put Debian\'s {" / ".join(plat.gcc)} on PATH)'
        ) from exc
    return [sys.executable, "-m", "ziglang", "cc", "-target", plat.zig_target]


#: glibc the Linux binaries are built for when Zig's C compiler is installed (``-target <arch>-linux-gnu.2.17``,
#: the manylinux2014 baseline); the system compiler links against the build machine's glibc instead.
GLIBC_BASELINE = (2, 17)


def zig_available() -> bool:
    """Is Zig's C compiler (the ``ziglang`` wheel, ``pendulab[cross]``) installed?

    Returns
    -------
    bool
        True when ``import ziglang`` succeeds.
    """
    try:
        import ziglang  # noqa: F401
    except ImportError:
        return False
    return True


def portable_host_compiler(cc: str | None = None) -> list[str] | None:
    """Compiler command for the host binary that targets an old glibc, or None for the system compiler.

    On a Linux host of :data:`PLATFORMS` with no compiler chosen (neither ``cc`` nor ``$CC``) and the
    ``ziglang`` wheel installed: ``python -m ziglang cc -target <arch>-linux-gnu.2.17``, so the binary loads
    on every glibc >= 2.17 (the system compiler would bind e.g. ``pow`` to the build machine's
    ``GLIBC_2.29``). Otherwise None: the host compiler as before (``$CC``, ``cc``, ``gcc``, ``clang``).

    Parameters
    ----------
    cc : str, optional
        Compiler the caller asked for; a given compiler is always used.

    Returns
    -------
    list of str or None
        Command and leading arguments, or None.
    """
    plat = PLATFORMS.get(host_platform())
    if cc or os.environ.get("CC") or plat is None or not plat.name.endswith("-linux") or not zig_available():
        return None
    return [sys.executable, "-m", "ziglang", "cc", "-target", plat.zig_target]


def runtime_requirement(data: bytes) -> str:
    """What a built binary needs from the system's C runtime, read from the file.

    ELF: the highest ``GLIBC_x.y`` symbol version it requires (``.gnu.version_r``; the versions
    ``objdump -T`` shows). PE (DLL): the C runtime DLLs it imports (UCRT's ``api-ms-win-crt-*.dll``,
    or ``msvcrt.dll``).

    Parameters
    ----------
    data : bytes
        Contents of a ``.so`` or ``.dll``.

    Returns
    -------
    str
        e.g. ``"glibc >= 2.14"``, ``"the Universal C Runtime (UCRT: api-ms-win-crt-*.dll)"``,
        ``"msvcrt.dll"``; ``"no glibc symbol versions"`` for an ELF file without any.

    Raises
    ------
    ValueError
        Not a 64-bit little-endian ELF or PE32+ file, or a damaged one.
    """
    try:
        if data[:4] == b"\x7fELF":
            versions = glibc_versions(data)
            return f"glibc >= {'.'.join(map(str, max(versions)))}" if versions else "no glibc symbol versions"
        if data[:2] == b"MZ":
            dlls = [d.lower() for d in _pe_imports(data)]
            crt = sorted({"api-ms-win-crt-*.dll" if d.startswith("api-ms-win-crt-") else d for d in dlls} - {"kernel32.dll"})
            if crt == ["api-ms-win-crt-*.dll"]:
                return "the Universal C Runtime (UCRT: api-ms-win-crt-*.dll)"
            return ", ".join(crt) if crt else "no C runtime DLL"
    except (struct.error, IndexError, UnicodeDecodeError) as exc:
        raise ValueError(f"damaged shared library: {exc}") from exc
    raise ValueError(f"not an ELF or PE file (starts with {data[:4]!r})")


def glibc_versions(data: bytes) -> tuple[tuple[int, ...], ...]:
    """The ``GLIBC_x.y[.z]`` versions an ELF shared library requires (its ``.gnu.version_r`` section).

    Parameters
    ----------
    data : bytes
        Contents of a 64-bit little-endian ELF file.

    Returns
    -------
    tuple of tuple of int
        Sorted, e.g. ``((2, 2, 5), (2, 14))``; empty when it needs none.

    Raises
    ------
    ValueError
        Not a 64-bit little-endian ELF file.
    """
    sections = _elf_sections(data)
    found = set()
    for sec in sections:
        if sec[1] != 0x6FFFFFFE:  # SHT_GNU_verneed
            continue
        strtab, off = sections[sec[6]][4], sec[4]
        for _ in range(sec[7]):  # sh_info: number of Verneed entries
            _, cnt, _, aux, nxt = struct.unpack_from("<HHIII", data, off)
            a = off + aux
            for _ in range(cnt):
                _, _, _, name, anext = struct.unpack_from("<IHHII", data, a)
                m = re.fullmatch(r"GLIBC_(\d+(?:\.\d+)+)", _cstr(data, strtab + name))
                if m:
                    found.add(tuple(int(p) for p in m.group(1).split(".")))
                a += anext
            off += nxt
    return tuple(sorted(found))


def _pe_imports(data: bytes) -> tuple[str, ...]:
    """Names of the DLLs a PE32+ file imports (its import directory)."""
    sections, opt = _pe_sections(data)
    import_rva, import_size = struct.unpack_from("<II", data, opt + 120)  # data directory 1
    if import_size == 0:
        return ()
    at = _rva_to_offset(sections)
    names, desc = [], at(import_rva)
    while True:
        entry = struct.unpack_from("<IIIII", data, desc)
        if entry == (0, 0, 0, 0, 0):
            return tuple(names)
        names.append(_cstr(data, at(entry[3])))
        desc += 20


def fmi_functions(header: str, fmi_version: int) -> tuple[str, ...]:
    """Every function an FMU must export, from the standard ``fmi{2,3}Functions.h`` text.

    Parameters
    ----------
    header : str
        Text of ``fmi2Functions.h`` or ``fmi3Functions.h``.
    fmi_version : {2, 3}
        FMI standard.

    Returns
    -------
    tuple of str
        Sorted names.
    """
    return tuple(sorted(set(re.findall(rf"#define\s+(fmi{fmi_version}\w+)\s+fmi{fmi_version}FullName\(", header))))


def exported_symbols(data: bytes) -> tuple[str, ...]:
    """Names of the functions a shared library exports, read from the file (ELF or PE).

    ELF: defined global/weak function symbols of ``.dynsym`` with default or protected
    visibility. PE (DLL): the names of the export directory.

    Parameters
    ----------
    data : bytes
        Contents of a ``.so`` or ``.dll``.

    Returns
    -------
    tuple of str
        Sorted names.

    Raises
    ------
    ValueError
        Not a 64-bit little-endian ELF or a PE32+ file, or a damaged one.
    """
    try:
        if data[:4] == b"\x7fELF":
            return _elf_exports(data)
        if data[:2] == b"MZ":
            return _pe_exports(data)
    except (struct.error, IndexError, UnicodeDecodeError) as exc:
        raise ValueError(f"damaged shared library: {exc}") from exc
    raise ValueError(f"not an ELF or PE file (starts with {data[:4]!r})")


def _cstr(data: bytes, offset: int) -> str:
    return data[offset : data.index(b"\0", offset)].decode("ascii")


def _elf_sections(data: bytes) -> list[tuple]:
    """The section header table of a 64-bit little-endian ELF file (``Elf64_Shdr`` fields in order)."""
    if data[4] != 2 or data[5] != 1:
        raise ValueError("only 64-bit little-endian ELF files are supported")
    (shoff,) = struct.unpack_from("<Q", data, 0x28)
    shentsize, shnum = struct.unpack_from("<HH", data, 0x3A)
    return [struct.unpack_from("<IIQQQQIIQQ", data, shoff + i * shentsize) for i in range(shnum)]


def _elf_exports(data: bytes) -> tuple[str, ...]:
    sections = _elf_sections(data)
    names = set()
    for sec in sections:
        if sec[1] != 11:  # SHT_DYNSYM
            continue
        offset, size, link, entsize = sec[4], sec[5], sec[6], sec[9]
        strtab = sections[link][4]
        for k in range(1, size // entsize):
            st_name, st_info, st_other, st_shndx = struct.unpack_from("<IBBH", data, offset + k * entsize)
            bind, typ, vis = st_info >> 4, st_info & 0xF, st_other & 0x3
            if st_shndx != 0 and bind in (1, 2) and typ == 2 and vis in (0, 3):  # GLOBAL/WEAK FUNC, DEFAULT/PROTECTED
                names.add(_cstr(data, strtab + st_name))
    return tuple(sorted(names))


def _pe_sections(data: bytes) -> tuple[list[tuple], int]:
    """(section table entries, offset of the optional header) of a PE32+ file."""
    (pe,) = struct.unpack_from("<I", data, 0x3C)
    if data[pe : pe + 4] != b"PE\0\0":
        raise ValueError("no PE signature")
    (n_sections,) = struct.unpack_from("<H", data, pe + 6)
    (opt_size,) = struct.unpack_from("<H", data, pe + 20)
    opt = pe + 24
    (magic,) = struct.unpack_from("<H", data, opt)
    if magic != 0x20B:
        raise ValueError("only PE32+ (64-bit) files are supported")
    sec_table = opt + opt_size
    return [struct.unpack_from("<8sIIII", data, sec_table + 40 * i) for i in range(n_sections)], opt


def _rva_to_offset(sections: list[tuple]):
    def at(rva: int) -> int:
        for _, vsize, vaddr, rawsize, rawptr in sections:
            if vaddr <= rva < vaddr + max(vsize, rawsize):
                return rawptr + rva - vaddr
        raise ValueError(f"RVA {rva:#x} outside every section")

    return at


def _pe_exports(data: bytes) -> tuple[str, ...]:
    sections, opt = _pe_sections(data)
    export_rva, export_size = struct.unpack_from("<II", data, opt + 112)  # data directory 0
    if export_size == 0:
        return ()
    at = _rva_to_offset(sections)
    exp = at(export_rva)
    (n_names,) = struct.unpack_from("<I", data, exp + 24)
    (names_rva,) = struct.unpack_from("<I", data, exp + 32)
    table = at(names_rva)
    return tuple(sorted(_cstr(data, at(struct.unpack_from("<I", data, table + 4 * i)[0])) for i in range(n_names)))


def read_exports(path: str | Path) -> tuple[str, ...]:
    """:func:`exported_symbols` of a file.

    Parameters
    ----------
    path : path-like
        Shared library.

    Returns
    -------
    tuple of str
        Sorted names.
    """
    return exported_symbols(Path(path).read_bytes())

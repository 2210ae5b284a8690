"""The output directory: written whole or not at all, and only sigmatau's own files replaced.

Holds the manifest of what sigmatau wrote (:data:`MANIFEST`, :func:`read_manifest`),
the checks before anything is written (:func:`check_output_dir`), the markers and
clean-up of temporary directories left by killed runs
(:func:`remove_stale_partials`) and the replacement of the listed files only.
Public through :mod:`sigmatau.outputs`.
"""

from __future__ import annotations

import json
import os
import shutil
import tempfile
from pathlib import Path
from typing import Any, Callable, Optional, Sequence, Union

from ..errors import ParameterError, SigmaTauError

__all__ = [
    "OutputExistsError", "umask", "MANIFEST", "PARTIAL_MARKER", "read_manifest", "check_output_dir",
    "remove_stale_partials", "write_directory", "write_text",
]


class OutputExistsError(SigmaTauError, FileExistsError):
    """The output directory exists and ``force`` was not given."""


def umask() -> int:
    """The process's file-creation mask (tempfile makes 0600/0700; outputs get the usual modes)."""
    mask = os.umask(0)
    os.umask(mask)
    return mask


def write_text(path: Path, text: str) -> None:
    """``text`` into ``path`` as UTF-8, newlines as given (into a staging folder of :func:`write_directory`)."""
    with open(path, "w", encoding="utf-8", newline="") as fh:
        fh.write(text)


_write_text = write_text


#: The file listing what sigmatau wrote into an output directory (name, size, SHA-256 of each):
#: ``force`` replaces those files and nothing else.
MANIFEST = "sigmatau-manifest.json"


#: Marker in sigmatau's temporary directories (``.OUT.partial-*``, ``.OUT.old-*``): host and PID of
#: the process that made it, so a later run removes it once that process is gone, and only it.
PARTIAL_MARKER = ".sigmatau-partial"


_MANIFEST_FORMAT = "sigmatau output manifest 1"


def _sha256(path: Path) -> str:
    import hashlib

    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def _entry(path: Path) -> dict[str, Any]:
    return {"name": path.name, "size": path.stat().st_size, "sha256": _sha256(path)}


def _manifest_text(entries: Sequence[dict[str, Any]], version: str) -> str:
    return json.dumps({"format": _MANIFEST_FORMAT, "tool": f"sigmatau {version}", "files": list(entries)},
                      indent=1) + "\n"


def _plain_name(name: Any) -> bool:
    """A file name of ours: no directory part, not '.', '..' or the manifest itself."""
    return (isinstance(name, str) and name not in ("", ".", "..", MANIFEST) and "/" not in name
            and "\\" not in name and "\x00" not in name)


def read_manifest(folder: Union[str, os.PathLike]) -> Optional[list[dict[str, Any]]]:
    """The files sigmatau recorded as its own in ``folder``; None when there is no valid manifest.

    Parameters
    ----------
    folder : path

    Returns
    -------
    list of dict or None
        One ``{"name", "size", "sha256"}`` per file (a name may appear twice
        while a replacement is under way: its old and its new content).
    """
    path = Path(folder) / MANIFEST
    if path.is_symlink() or not path.is_file():
        return None
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    if not isinstance(data, dict) or data.get("format") != _MANIFEST_FORMAT or not isinstance(data.get("files"), list):
        return None
    files = [f for f in data["files"] if isinstance(f, dict) and _plain_name(f.get("name"))
             and isinstance(f.get("size"), int) and isinstance(f.get("sha256"), str)]
    return files if len(files) == len(data["files"]) else None


def _ours(folder: Path, entries: Sequence[dict[str, Any]]) -> list[str]:
    """The listed files present in ``folder`` (a changed one is refused: it may hold the user's edits)."""
    names: list[str] = []
    for name in dict.fromkeys(e["name"] for e in entries):
        path = folder / name
        if not os.path.lexists(path):
            continue
        versions = [(e["size"], e["sha256"]) for e in entries if e["name"] == name]
        if path.is_symlink() or not path.is_file() or (path.stat().st_size, _sha256(path)) not in versions:
            raise OutputExistsError(f"{name!r} in {str(folder)!r} changed since sigmatau wrote it; move it"
                                    " elsewhere first, sigmatau replaces only its own unchanged files")
        names.append(name)
    return names


#: Files every analysis writes (figures depend on the channels); checked before the analysis runs.
_FIXED_NAMES = ("results.json", "statistics.csv", "model.csv", "imu.yaml", "report.html")


def check_output_dir(out_dir: Union[str, os.PathLike], *, force: bool = False,
                     protect: Sequence[Union[str, os.PathLike]] = ()) -> None:
    """Refuse, before any computation, an output directory :func:`~sigmatau.outputs.write_outputs` would refuse.

    Allowed: a directory that does not exist (in an existing parent); with
    ``force``, an empty directory or one sigmatau wrote (it holds
    ``sigmatau-manifest.json``), whose listed files are replaced if unchanged
    and whose other files are left alone. Never the current directory, its
    parents or the home directory, nor a directory holding a path of
    ``protect``.

    Raises
    ------
    OutputExistsError
        ``out_dir`` exists and ``force`` is not given, it is not a directory,
        it is not a sigmatau output, or a file sigmatau wrote there was changed.
    ParameterError
        ``out_dir`` is the current directory, one of its parents or the home
        directory, its parent does not exist, or it contains a path of ``protect``
        (the input).
    """
    out = Path(out_dir)
    target = out.resolve()
    cwd = Path.cwd().resolve()
    if target == cwd or target in cwd.parents or target == Path.home().resolve():
        raise ParameterError(f"the output directory {str(out)!r} is the current directory, one of its parents or"
                             " the home directory; choose a directory of its own")
    for p in protect:
        q = Path(p).resolve()
        if q == target or target in q.parents:
            raise ParameterError(f"the output directory {str(out)!r} contains the input {str(p)!r}; choose another"
                                 " output directory")
    if os.path.lexists(out) and not out.is_dir():
        raise OutputExistsError(f"{str(out)!r} exists and is not a directory; choose another output directory")
    if not target.parent.is_dir():
        raise ParameterError(f"the parent directory of {str(out)!r} does not exist")
    if not out.exists():
        return
    if not any(out.iterdir()):
        if not force:
            raise OutputExistsError(f"output directory {str(out)!r} exists (empty); use --force to write into it")
        return
    entries = read_manifest(out)
    if entries is None:
        raise OutputExistsError(f"{str(out)!r} exists and is not a sigmatau output directory (no {MANIFEST});"
                                " choose another output directory")
    if not force:
        raise OutputExistsError(f"output directory {str(out)!r} exists; use --force to replace the sigmatau"
                                " outputs in it")
    ours = set(_ours(out, entries))
    for name in _FIXED_NAMES:
        if name not in ours and os.path.lexists(out / name):
            raise OutputExistsError(f"{name!r} in {str(out)!r} is not a file sigmatau wrote; move it elsewhere"
                                    " first")


def _pid_alive(pid: int) -> bool:
    if os.name == "nt":  # os.kill(pid, 0) would terminate the process there: never judge, keep the directory
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except (PermissionError, OverflowError, ValueError):
        return True  # someone else's process, or not a PID we can judge: keep its directory
    return True


def _mark(folder: Path) -> None:
    import socket

    _write_text(folder / PARTIAL_MARKER, json.dumps({"host": socket.gethostname(), "pid": os.getpid()}) + "\n")


def remove_stale_partials(parent: Union[str, os.PathLike]) -> list[Path]:
    """Remove the temporary directories sigmatau left in ``parent`` when a run was killed.

    Only directories named ``.*.partial-*`` or ``.*.old-*`` that hold
    sigmatau's marker naming this host and a process that no longer exists;
    a directory of a running process, of another host or without the marker
    is left alone.

    Returns
    -------
    list of Path
        The directories removed.
    """
    import socket

    removed: list[Path] = []
    folder = Path(parent)
    candidates = [*folder.glob(".*.partial-*"), *folder.glob(".*.old-*")]
    for d in candidates:
        marker = d / PARTIAL_MARKER
        if d.is_symlink() or not d.is_dir() or marker.is_symlink() or not marker.is_file():
            continue
        try:
            who = json.loads(marker.read_text(encoding="utf-8"))
            host, pid = who["host"], int(who["pid"])
        except (OSError, ValueError, KeyError, TypeError):
            continue
        if host != socket.gethostname() or pid == os.getpid() or _pid_alive(pid):
            continue
        shutil.rmtree(d, ignore_errors=True)
        removed.append(d)
    return removed


def _replace_files(new: Path, target: Path, entries: list[dict[str, Any]], version: str) -> None:
    """Move the files of ``new`` into the existing ``target``, replacing only sigmatau's own files.

    The previous files go to a marked backup directory first and come back if
    anything fails; while files move, the manifest lists old and new
    versions, so a run killed half-way leaves a directory a later ``--force``
    still recognises.
    """
    old_entries = read_manifest(target) or []
    old_text = (target / MANIFEST).read_text(encoding="utf-8") if old_entries else None
    ours = _ours(target, old_entries)
    for e in entries:
        if e["name"] not in ours and os.path.lexists(target / e["name"]):
            raise OutputExistsError(f"{e['name']!r} in {str(target)!r} is not a file sigmatau wrote; move it"
                                    " elsewhere first")
    backup = Path(tempfile.mkdtemp(prefix=f".{target.name}.old-", dir=target.parent))
    moved: list[str] = []
    placed: list[str] = []
    try:
        _mark(backup)
        _replace_manifest(target, _manifest_text([*old_entries, *entries], version))
        for name in ours:
            os.replace(target / name, backup / name)
            moved.append(name)
        for e in entries:
            os.replace(new / e["name"], target / e["name"])
            placed.append(e["name"])
        _replace_manifest(target, _manifest_text(entries, version))
    except BaseException:
        for name in placed:  # put everything back as it was
            os.replace(target / name, new / name)
        for name in moved:
            os.replace(backup / name, target / name)
        if old_text is not None:
            _replace_manifest(target, old_text)
        elif (target / MANIFEST).exists():
            os.unlink(target / MANIFEST)
        shutil.rmtree(backup, ignore_errors=True)
        raise
    shutil.rmtree(backup, ignore_errors=True)


def _replace_manifest(folder: Path, text: str) -> None:
    fd, tmp = tempfile.mkstemp(prefix=".sigmatau-manifest.", suffix=".partial", dir=folder)
    try:
        with os.fdopen(fd, "w", encoding="utf-8") as fh:
            fh.write(text)
        os.chmod(tmp, 0o666 & ~umask())
        os.replace(tmp, folder / MANIFEST)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise


def write_directory(out_dir: Union[str, os.PathLike], fill: Callable[[Path], None], version: str, *,
                    force: bool = False, protect: Sequence[Union[str, os.PathLike]] = ()) -> list[Path]:
    """Make ``out_dir`` whole or not at all: ``fill(folder)`` writes the files into a staging folder.

    The staging folder is a temporary sibling marked with this process's PID
    (:func:`remove_stale_partials`, called here, removes those of killed runs). A
    new ``out_dir`` is that folder renamed into place. An existing one is accepted
    only with ``force`` and only if it is empty or sigmatau wrote it
    (:data:`MANIFEST`, :func:`check_output_dir`): then the files sigmatau wrote
    there before are replaced (put back if anything fails) and every other file is
    left as it is. The manifest lists the files written, with sizes and SHA-256.

    Returns
    -------
    list of Path
        The files written, in ``out_dir`` (the manifest included).
    """
    out = Path(out_dir)
    target = out.resolve()
    check_output_dir(out, force=force, protect=protect)
    parent = target.parent
    remove_stale_partials(parent)
    tmp = Path(tempfile.mkdtemp(prefix=f".{target.name}.partial-", dir=parent))
    try:
        _mark(tmp)
        fill(tmp)
        os.unlink(tmp / PARTIAL_MARKER)
        entries = [_entry(p) for p in sorted(tmp.iterdir()) if p.is_file()]
        if out.exists():
            _replace_files(tmp, target, entries, version)
            shutil.rmtree(tmp, ignore_errors=True)
        else:
            write_text(tmp / MANIFEST, _manifest_text(entries, version))
            os.chmod(tmp, 0o777 & ~umask())  # mkdtemp makes 0700; give the folder the usual mode
            os.replace(tmp, target)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    return sorted(target / n for n in [*(e["name"] for e in entries), MANIFEST])

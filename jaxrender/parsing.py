"""Text a user types, read one way everywhere: resolutions ("1920x1080"), ``key=value``
settings with TOML values, and ``name:key=value,...`` specs. Errors are UserErrors that name
where the text came from (a flag, a study key)."""

from __future__ import annotations

import argparse
import tomllib

from jaxrender.errors import UserError

MAX_SIDE = 8192  # pixels per image side: beyond it a frame no longer fits a device's memory


def parse_resolution(value, where: str = "resolution") -> tuple[int, int]:
    """'WxH' (either case of x) or [W, H] -> (W, H); a UserError naming ``where`` otherwise."""
    msg = f"{where}: expected 'WxH' or [width, height] with integers in 1..{MAX_SIDE}"
    if isinstance(value, str):
        parts = value.lower().split("x")
        if len(parts) != 2 or not all(p.strip().isdigit() for p in parts):
            raise UserError(f"{msg}, got {value!r}")
        w, h = (int(p) for p in parts)
    elif isinstance(value, (list, tuple)) and len(value) == 2:
        if not all(isinstance(v, int) and not isinstance(v, bool) for v in value):
            raise UserError(f"{msg}, got {value!r}")
        w, h = value
    else:
        raise UserError(f"{msg}, got {value!r}")
    if not (1 <= w <= MAX_SIDE and 1 <= h <= MAX_SIDE):
        raise UserError(f"{msg}, got {w}x{h}")
    return int(w), int(h)


def resolution_arg(text: str) -> tuple[int, int]:
    """``parse_resolution`` as an argparse ``type=``: argparse names the flag itself."""
    try:
        return parse_resolution(text, "")
    except UserError as e:
        raise argparse.ArgumentTypeError(str(e).removeprefix(": ")) from None


def positive_int_arg(text: str) -> int:
    """An integer >= 1 as an argparse ``type=``: argparse names the flag itself."""
    try:
        n = int(text)
    except ValueError:
        n = 0
    if n < 1:
        raise argparse.ArgumentTypeError(f"expected a positive integer, got {text!r}")
    return n


def parse_value(text: str):
    """A TOML value (``4``, ``0.5``, ``true``, ``[1, 2]``, ``"s"``); a bare word is a string."""
    try:
        return tomllib.loads(f"v = {text}")["v"]
    except tomllib.TOMLDecodeError:
        return text.strip()


def parse_setting(text: str, where: str) -> tuple[str, object]:
    """'key=value' -> (key, value) with a TOML value; a UserError naming ``where`` when there
    is no '=' or no key."""
    key, eq, value = text.partition("=")
    if not eq or not key.strip():
        raise UserError(f"{where} {text!r}: expected key=value")
    return key.strip(), parse_value(value)


def parse_settings(items, where: str) -> dict:
    """Every 'key=value' of ``items`` (a later key wins), as ``parse_setting``."""
    return dict(parse_setting(item, where) for item in items or ())


def parse_spec(text: str, where: str = "spec") -> tuple[str, dict]:
    """'name' or 'name:key=value,key=value' -> (name, {key: value}), as ``parse_setting``."""
    name, _, rest = text.partition(":")
    return name.strip(), parse_settings(filter(None, rest.split(",")), f"{where} {text!r}:")


def help_summary(doc: str) -> str:
    """A command's ``--help`` description from its module docstring: the first paragraph,
    joined into one line (argparse wraps it), so that it never stops mid-sentence."""
    lines = []
    for line in (doc or "").strip().splitlines():
        if not line.strip():
            break
        lines.append(line.strip())
    return " ".join(lines)

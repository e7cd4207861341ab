"""Text of messages: values shortened, messages on one line, sizes in bytes.

Values echoed in error messages come from the user's input; :func:`shorten`
formats only the part it shows, so that a hostile input (a 50 MB string, a
list of millions of numbers, an array nested 100,000 deep) gives a short
line.  It shows values as the user wrote them, not as Python holds them: a
TOML date as ``1979-05-27 (a date)``, numpy arrays and numbers as lists and
plain numbers, an integer beyond 64 bits as ``1e+30``.
"""

from __future__ import annotations

import datetime
import sys

__all__ = ["format_bytes", "one_line", "shorten"]

# Longest message line, characters: a safety net behind shorten().
_MAX_LINE = 500

_GIB = 2 ** 30

# Integers this large or larger are shown as ``1e+30``: beyond 64 bits, digits tell nothing.
_LONG_INTEGER = 10 ** 19


def _short(value, limit, depth):
    """``repr`` of ``value`` in about ``limit`` characters; never the whole of a huge value."""
    if depth > 6:
        return "..."
    value = _plain(value)
    if isinstance(value, (datetime.date, datetime.time)):
        return _toml_time(value)
    if isinstance(value, int) and not isinstance(value, bool) and abs(value) >= _LONG_INTEGER:
        if value.bit_length() < 1000:
            return f"{value:.6g}"
        return f"{'-' if value < 0 else ''}an integer of {value.bit_length()} bits"
    if isinstance(value, (str, bytes)):
        if len(value) <= limit:
            return repr(value)
        unit = "characters" if isinstance(value, str) else "bytes"
        return f"{value[:limit]!r}... ({len(value)} {unit})"
    if isinstance(value, (list, tuple, dict)) or _is_array(value):
        if isinstance(value, dict):
            opening, closing, noun, items = "{", "}", "keys", value.items()
        elif isinstance(value, tuple):
            opening, closing, noun, items = "(", ")", "items", value
        else:
            opening, closing, noun, items = "[", "]", "items", value
        parts, length = [], 0
        for count, item in enumerate(items):
            if length > limit:
                return (f"{opening}{', '.join(parts)}, ...{closing} "
                        f"({len(value)} {noun}, {len(value) - count} not shown)")
            if isinstance(value, dict):
                text = f"{_short(item[0], limit, depth + 1)}: {_short(item[1], limit, depth + 1)}"
            else:
                text = _short(item, limit, depth + 1)
            parts.append(text)
            length += len(text) + 2
        if len(value) == 1 and isinstance(value, tuple):
            return f"({parts[0]},)"
        return f"{opening}{', '.join(parts)}{closing}"
    try:
        text = repr(value)
    except RecursionError:
        return f"<{type(value).__name__} nested too deeply to show>"
    if len(text) > limit:
        return f"{text[:limit]}... ({len(text)} characters)"
    return text


def _plain(value):
    """A numpy number (or a 0-d array) as the Python number it holds; anything else as it is."""
    numpy = sys.modules.get("numpy")  # a numpy value exists only once numpy is loaded
    if numpy is not None and (isinstance(value, numpy.generic) or (
            isinstance(value, numpy.ndarray) and value.ndim == 0)):
        return value.item()
    return value


def _is_array(value):
    """Whether ``value`` is a numpy array (shown as nested lists)."""
    numpy = sys.modules.get("numpy")
    return numpy is not None and isinstance(value, numpy.ndarray)


def _toml_time(value):
    """A date, a time or a date-time as TOML writes it, saying which it is."""
    if isinstance(value, datetime.datetime):
        return f"{value.isoformat()} (a date-time)"
    if isinstance(value, datetime.date):
        return f"{value.isoformat()} (a date)"
    return f"{value.isoformat()} (a time of day)"


def shorten(value, limit=80):
    """``repr`` of a value for a message, at most about ``limit`` characters.

    Parameters
    ----------
    value : object
        A value read from the user's input.
    limit : int, optional
        Characters of the value to show (default 80).

    Returns
    -------
    str
        ``repr(value)`` when it is short; otherwise its beginning and what
        was left out.  Only the part shown is ever formatted, so a list of
        millions of numbers or an array nested 100,000 deep costs nothing.
        Values are shown as a scene file writes them: a date (which TOML
        reads where a number was meant) as a date, numpy arrays as lists,
        numpy numbers as numbers, integers beyond 64 bits as ``1e+30``.

    Examples
    --------
    >>> shorten([1.0, 2.0])
    '[1.0, 2.0]'
    >>> shorten([1e-9] * 7_000_000, limit=20)
    '[1e-09, 1e-09, 1e-09, ...] (7000000 items, 6999997 not shown)'
    >>> shorten("x" * 50_000_000, limit=10)
    "'xxxxxxxxxx'... (50000000 characters)"
    >>> import datetime, numpy as np
    >>> shorten(datetime.date(1979, 5, 27)), shorten(10 ** 30)
    ('1979-05-27 (a date)', '1e+30')
    >>> shorten(np.array([[500.0, 20.0]])), shorten(np.float64(0.5))
    ('[[500.0, 20.0]]', '0.5')
    """
    return _short(value, int(limit), 0)


def one_line(text, limit=_MAX_LINE):
    """A message as one line of at most about ``limit`` characters.

    Parameters
    ----------
    text : str
    limit : int, optional
        Characters kept (default 500).

    Returns
    -------
    str

    Examples
    --------
    >>> one_line(ValueError("two" + chr(10) + "lines"))
    'two lines'
    """
    text = " ".join(str(text).split("\n"))
    if len(text) > limit:
        return f"{text[:limit]}... (message of {len(text)} characters shortened)"
    return text


def format_bytes(value):
    """Bytes as ``'1.5 GiB'``, ``'20 MiB'`` or ``'512 bytes'``.

    Examples
    --------
    >>> format_bytes(3 * 2**30 // 2), format_bytes(20 * 2**20), format_bytes(512)
    ('1.5 GiB', '20 MiB', '512 bytes')
    """
    if value >= 100 * _GIB:
        return f"{value / _GIB:.0f} GiB"
    if value >= _GIB:
        return f"{value / _GIB:.3g} GiB"
    if value >= 2 ** 20:
        return f"{value / 2 ** 20:.3g} MiB"
    return f"{int(value)} bytes"

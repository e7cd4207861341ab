"""Input arrays read from files: ``.npy`` arrays and PNG images, checked before their data.

A scene names files (phase maps, face masks, micrographs, initial faces);
every one is checked before its data are read: it exists and is a regular
file, is not empty, has a valid header (a ``.npy`` header or a PNG
signature), announces a shape and a type of number the caller accepts, and
holds the bytes its header announces -- so that an empty, truncated,
foreign or oversized file is refused with a message naming it, never an
``EOFError`` or a ``MemoryError`` half-way.

What a ``.npy`` file may hold is one :class:`Holds` per kind of array
(:data:`REAL_NUMBERS` for heights and recessions, :data:`INTEGERS`,
:data:`LABELS`, :data:`MASK`, :data:`NUMBERS`), stated by every reader.
No array of the project is complex: numpy would keep the real part of
one, and make heights of 0 and 1 of a boolean one, without a word.
"""

from __future__ import annotations

import dataclasses
import math
import pathlib
import stat

import numpy as np

from .text import format_bytes

__all__ = ["INTEGERS", "LABELS", "MASK", "NUMBERS", "PNG_SIGNATURE", "REAL_NUMBERS", "Holds",
           "array_suffix", "input_file_size", "integer_face", "npy_header", "png_size",
           "read_face_mask", "read_npy", "read_png"]


@dataclasses.dataclass(frozen=True)
class Holds:
    """What an array read from a file may hold: numpy dtype kinds, and their name.

    Parameters
    ----------
    kinds : str
        The :attr:`numpy.dtype.kind` letters accepted (``"b"`` booleans,
        ``"i"``, ``"u"`` integers, ``"f"`` floats).
    words : str
        What they are, for messages (``"real numbers"``).

    Examples
    --------
    >>> REAL_NUMBERS.check(np.dtype(np.float32), "initial face file 'h.npy'")
    >>> try:
    ...     REAL_NUMBERS.check(np.dtype(complex), "initial face file 'h.npy'")
    ... except ValueError as err:
    ...     print(err)
    initial face file 'h.npy' holds complex numbers (complex128); it must hold real numbers
    """

    kinds: str
    words: str

    def check(self, dtype, what):
        """``ValueError`` naming ``what`` (the array or its file) unless ``dtype`` is accepted."""
        dtype = np.dtype(dtype)
        if dtype.kind in self.kinds:
            return
        if dtype.kind in "cb":  # what numpy converts to floats without an error
            found = "complex numbers" if dtype.kind == "c" else "booleans"
            raise ValueError(f"{what} holds {found} ({dtype}); it must hold {self.words}")
        raise ValueError(f"{what} must hold {self.words}, got dtype {dtype}")


#: Heights and recessions, m: an initial face, a measured map.
REAL_NUMBERS = Holds("iuf", "real numbers")
#: Phase indices of a voxel stack.
INTEGERS = Holds("iu", "integers")
#: A phase map: integers, or booleans for two phases.
LABELS = Holds("biu", "integers")
#: A face mask: booleans, or integers in one of the forms :func:`integer_face` reads.
MASK = Holds("biu", "booleans (True on the face) or integers (0/1, or -1 off the face)")
#: Grey levels of an image (a micrograph): any real numbers or booleans.
NUMBERS = Holds("biuf", "real numbers or booleans")


def input_file_size(path, what):
    """Size in bytes of an input file; ``ValueError`` unless it is a readable regular file."""
    try:
        st = path.stat()
    except FileNotFoundError:
        raise ValueError(f"{what} {str(path)!r} does not exist") from None
    except OSError as err:
        raise ValueError(f"cannot read {what} {str(path)!r}: {err.strerror or err}") from None
    if stat.S_ISDIR(st.st_mode):
        raise ValueError(f"{what} {str(path)!r} is a directory, not a file")
    if not stat.S_ISREG(st.st_mode):
        raise ValueError(f"{what} {str(path)!r} is not a regular file (a device or a pipe?)")
    if st.st_size == 0:
        raise ValueError(f"{what} {str(path)!r} is empty (0 bytes)")
    return st.st_size


def npy_header(path, *, what="file", holds=NUMBERS, shape=None, max_side=None, square=True):
    """Shape and dtype of a ``.npy`` file, read from its header without loading the data.

    Parameters
    ----------
    path : str or path-like
    what : str, optional
        How messages name the file (e.g. ``"phase map"``).
    holds : Holds, optional
        What the array may hold (default :data:`NUMBERS`: real numbers or
        booleans, never complex).
    shape : tuple of int, optional
        Refuse any other shape.
    max_side : int, optional
        Refuse anything but a square 2-d array of at most
        ``max_side x max_side`` values.
    square : bool, optional
        With ``max_side``: whether the array must be square (default True);
        if not, any 2-d array whose longer side is at most ``max_side``.

    Returns
    -------
    shape : tuple of int
    dtype : numpy.dtype

    Raises
    ------
    ValueError
        Missing file, a directory or device, an empty file, no ``.npy``
        header, a damaged header, an array of Python objects or of numbers
        ``holds`` refuses, a shape refused by ``shape`` or ``max_side``, or
        fewer data bytes than the header announces (a truncated file, or a
        header that claims a huge array).
    """
    import numpy.lib.format as npy_format

    path = pathlib.Path(path)
    size = input_file_size(path, what)
    try:
        with open(path, "rb") as f:
            if f.read(6) != npy_format.MAGIC_PREFIX:
                magic = False
            else:
                magic = True
                f.seek(0)
                version = npy_format.read_magic(f)
                read = (npy_format.read_array_header_1_0 if version == (1, 0)
                        else npy_format.read_array_header_2_0)
                found, _, dtype = read(f)
                offset = f.tell()
    except OSError as err:
        raise ValueError(f"cannot read {what} {str(path)!r}: {err.strerror or err}") from None
    except Exception as err:  # noqa: BLE001 -- numpy parses the header with Python's tokenizer
        raise ValueError(f"{what} {str(path)!r} has a damaged .npy header: "
                         f"{str(err)[:200]}") from None
    if not magic:
        raise ValueError(f"{what} {str(path)!r} is not a .npy file (no NumPy header)")
    found = tuple(found)
    if dtype.hasobject:
        raise ValueError(f"{what} {str(path)!r} holds Python objects, not numbers")
    holds.check(dtype, f"{what} {str(path)!r}")
    if shape is not None and found != tuple(shape):
        raise ValueError(f"{what} {str(path)!r} holds an array of shape {found}; "
                         f"{tuple(shape)} is needed")
    if max_side is not None:
        if len(found) != 2 or (square and found[0] != found[1]):
            kind = "square 2-d" if square else "2-d"
            raise ValueError(f"{what} {str(path)!r} must be a {kind} array, got shape "
                             f"{found}")
        if max(found) > max_side:
            raise ValueError(f"{what} {str(path)!r} has {found[0]} x {found[1]} pixels, more "
                             f"than the grid's n = {max_side} (n must be a multiple of the "
                             f"map's size)")
    needed = math.prod(found) * dtype.itemsize
    if size - offset < needed:
        dims = " x ".join(str(d) for d in found) or "scalar"
        raise ValueError(f"{what} {str(path)!r} is truncated: its header announces {dims} "
                         f"values of {dtype} ({format_bytes(needed)}), the file holds "
                         f"{size - offset} bytes of data")
    return found, dtype


def read_npy(path, *, what="file", holds, max_side=None, shape=None, square=True):
    """Read a 2-d array (square by default) from a ``.npy`` file, checking the file first.

    Parameters
    ----------
    path : str or path-like
    what : str, optional
        How messages name the file (e.g. ``"phase map"``).
    holds : Holds
        What the array may hold (:data:`REAL_NUMBERS`, :data:`LABELS`, ...),
        checked from the header.
    max_side : int, optional
        Refuse arrays larger than ``max_side x max_side`` (before loading).
    shape : tuple of int, optional
        Refuse any other shape (before loading).
    square : bool, optional
        Refuse arrays that are not square (default True).

    Returns
    -------
    ndarray, shape (m, m), or (mx, my) if not ``square``

    Raises
    ------
    ValueError
        As :func:`npy_header`, or not square 2-d.  Never ``EOFError`` or
        ``MemoryError``.

    Examples
    --------
    >>> import pathlib, tempfile
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "empty.npy"
    >>> _ = path.write_bytes(b"")
    >>> try:
    ...     read_npy(path, what="phase map", holds=LABELS)
    ... except ValueError as err:
    ...     print(str(err).replace(str(path), "empty.npy"))
    phase map 'empty.npy' is empty (0 bytes)
    """
    path = pathlib.Path(path)
    found, dtype = npy_header(path, what=what, holds=holds, shape=shape, square=square,
                              max_side=math.inf if max_side is None else max_side)
    try:
        return np.load(path, allow_pickle=False)
    except (OSError, ValueError, EOFError) as err:
        raise ValueError(f"cannot read {what} {str(path)!r}: {str(err)[:200]}") from None
    except MemoryError:
        raise ValueError(f"{what} {str(path)!r} ({found[0]} x {found[1]} values of {dtype}) "
                         f"does not fit in memory") from None


def read_face_mask(path):
    """The face of a ``.npy`` or ``.png`` file, as pixels: ``True`` on the face.

    Parameters
    ----------
    path : str or path-like
        ``.npy``: a 2-d array, either booleans (``True`` on the face) or
        integers in one of two forms (:func:`integer_face`): only 0 and 1
        (1 on the face, a 0/1 image), or -1 off the face and values
        ``>= 0`` on it (a phase map with -1 off its face is its own mask).
        Any other integers are refused, with the values found: nothing
        else says unambiguously which pixels are off the face.
        ``.png``: an image with an alpha channel; the face is its
        non-transparent pixels.  Rows run along x, as in phase maps.

    Returns
    -------
    ndarray of bool, shape (mx, my)

    Raises
    ------
    ValueError
        Missing, empty, truncated or unreadable file, an unsupported
        suffix or dtype, integers of neither form, a PNG without alpha
        channel, no face pixel.
    """
    path = pathlib.Path(path)
    what = "face mask"
    if array_suffix(path, what) == ".npy":
        a = read_npy(path, what=what, holds=MASK, square=False)
        if a.size == 0:
            raise ValueError(f"{what} {str(path)!r} is empty: an array of shape {a.shape}")
        mask = a if a.dtype == bool else integer_face(a, f"{what} {str(path)!r}")
    else:
        img = read_png(path, what)
        if img.ndim != 3 or img.shape[2] not in (2, 4):
            raise ValueError(f"{what} {str(path)!r} has no alpha channel: the face is the "
                             f"non-transparent pixels of a PNG (or use a .npy array)")
        mask = img[..., -1] > 0
    if mask.ndim != 2 or not mask.any():
        raise ValueError(f"{what} {str(path)!r} has no face pixel")
    return np.ascontiguousarray(mask)


def integer_face(values, what="face mask"):
    """The face pixels an integer mask marks: ``True`` on the face.

    The rule (docs/scenes.md, ``[punch] shape = "mask"``): an integer mask holds
    either only 0 and 1, 1 on the face (a 0/1 image), or -1 off the face
    and values ``>= 0`` on it (a phase map with -1 off its face, the
    convention of phase-map files, is its own mask).  Any other set of
    values -- ``{0, 2, 7}``, ``{0, -2}``, ``{-1, -2, 0}`` -- does not say
    which pixels are off the face and is refused with the values found,
    rather than read as a face of every pixel.

    Parameters
    ----------
    values : ndarray of int, shape (mx, my)
    what : str, optional
        How the message names the mask (e.g. ``"face mask 'm.npy'"``).

    Returns
    -------
    ndarray of bool, shape (mx, my)

    Raises
    ------
    ValueError
        Integers of neither form; the message lists the distinct values
        (the first and last few of many).

    Examples
    --------
    >>> integer_face(np.array([[0, 1], [1, 1]], dtype=np.uint8)).tolist()
    [[False, True], [True, True]]
    >>> integer_face(np.array([[-1, 0], [2, 1]])).tolist()
    [[False, True], [True, True]]
    >>> try:
    ...     integer_face(np.array([[0, 2], [7, 7]]))
    ... except ValueError as err:
    ...     print(err)
    face mask holds the integer values [0, 2, 7]: an integer mask must hold only 0 and 1 (1 on
    the face) or -1 off the face and values >= 0 on it; use a boolean array (True on the face)
    """
    values = np.asarray(values)
    found = np.unique(values)
    if found.size and found[0] >= 0 and found[-1] <= 1:
        return values == 1
    if found.size and found[0] == -1 and (found.size == 1 or found[1] >= 0):
        return values != -1
    shown = found.tolist()
    listed = (str(shown) if len(shown) <= 12
              else f"[{', '.join(map(str, shown[:6]))}, ..., {', '.join(map(str, shown[-3:]))}]"
                   f" ({len(shown)} distinct values)")
    raise ValueError(f"{what} holds the integer values {listed}: an integer mask must hold "
                     f"only 0 and 1 (1 on the face) or -1 off the face and values >= 0 on it; "
                     f"use a boolean array (True on the face)")


#: The eight bytes every PNG file starts with.
PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"


def png_size(path, what):
    """Width and height from a PNG's header, once its chunks are found complete.

    The file is walked chunk by chunk (length, type, data, checksum) without
    decoding: it must start with the PNG signature, then the header chunk
    ``IHDR`` of a size of at least 1 x 1, hold image data (``IDAT``) and end
    with ``IEND``, every chunk within the file.  A file cut short -- down
    to the signature alone -- is refused here, naming what is missing,
    rather than met by the decoder.

    Parameters
    ----------
    path : str or path-like
    what : str
        How messages name the file (e.g. ``"phase map"``).

    Returns
    -------
    (int, int)
        Width and height, pixels.

    Raises
    ------
    ValueError
        The file cannot be read, has no PNG signature, or its chunks are
        incomplete; the message names the file as ``what``.

    Examples
    --------
    >>> import pathlib, tempfile
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "cut.png"
    >>> _ = path.write_bytes(PNG_SIGNATURE)
    >>> try:
    ...     png_size(path, "phase map")
    ... except ValueError as err:
    ...     print(str(err).replace(str(path), "cut.png"))
    phase map 'cut.png' is not a readable PNG image: it holds only the 8-byte PNG signature
    """
    name = f"{what} {str(path)!r}"
    try:
        with open(path, "rb") as f:
            if f.read(8) != PNG_SIGNATURE:
                raise ValueError(f"{name} is not a PNG image (no PNG signature)")
            size, chunks, header = _png_chunks(f, name)
    except OSError as err:
        raise ValueError(f"cannot read {name}: {err.strerror or err}") from None
    broken = f"{name} is not a readable PNG image"
    if header is None:
        raise ValueError(f"{broken}: it starts with a chunk {chunks[0]!r}, not the 13-byte "
                         f"image header IHDR")
    width, height = int.from_bytes(header[:4], "big"), int.from_bytes(header[4:8], "big")
    if not (width and height):
        raise ValueError(f"{broken}: its header gives {width} x {height} pixels")
    if "IDAT" not in chunks:
        raise ValueError(f"{broken}: it holds no image data (no IDAT chunk in {size} bytes)")
    if chunks[-1] != "IEND":
        raise ValueError(f"{broken}: it is truncated after {size} bytes (no IEND chunk)")
    return width, height


def _png_chunks(f, name):
    """A PNG's size, its chunk types up to ``IEND`` and its header, read past the signature.

    Returns ``(size, types, header)``: the file's size in bytes, the chunk
    types in order (``"IHDR"``, ``"IDAT"``, ...) and the 13 bytes of the
    first chunk if it is the header ``IHDR``, else None.  ``ValueError``
    for a file that holds only the signature or a chunk that runs past the
    file's end (a file truncated in its middle).
    """
    size = f.seek(0, 2)
    offset, types, header = 8, [], None
    if size == offset:
        raise ValueError(f"{name} is not a readable PNG image: it holds only the 8-byte PNG "
                         f"signature")
    while offset < size:
        f.seek(offset)
        head = f.read(8)
        length = int.from_bytes(head[:4], "big")
        kind = head[4:8].decode("latin-1")
        end = offset + 12 + length  # length, type, data, checksum
        if len(head) < 8 or end > size:
            inside = f"inside a chunk {kind!r}" if len(head) == 8 else "inside a chunk's length"
            raise ValueError(f"{name} is not a readable PNG image: it is truncated after "
                             f"{size} bytes, {inside}")
        if not types and kind == "IHDR" and length == 13:
            header = f.read(13)
        types.append(kind)
        offset = end
        if kind == "IEND":
            break
    return size, types, header


def array_suffix(path, what):
    """``".npy"`` or ``".png"``, the suffix of an array file; ``ValueError`` for any other.

    A file that does not exist is named as missing rather than as of the
    wrong kind.
    """
    suffix = pathlib.Path(path).suffix.lower()
    if suffix not in (".npy", ".png"):
        input_file_size(path, what)
        raise ValueError(f"{what} {str(path)!r} must be a .npy or .png file")
    return suffix


def read_png(path, what, check_size=None):
    """The pixels of a PNG image, checked from its header before it is decoded.

    Parameters
    ----------
    path : str or path-like
    what : str
        How messages name the file (e.g. ``"phase map"``).
    check_size : callable, optional
        ``check_size((width, height))``, called with the header's size
        before the image is decoded; raises ``ValueError`` to refuse it.

    Returns
    -------
    ndarray, shape (rows, cols) or (rows, cols, channels)
        As :func:`matplotlib.image.imread` decodes it (floats in [0, 1]).

    Raises
    ------
    ValueError
        Missing, empty or unreadable file, no PNG signature, a size refused
        by ``check_size``, or a decoder failure.
    """
    import matplotlib.image  # deferred: only PNG files need it

    input_file_size(pathlib.Path(path), what)
    size = png_size(path, what)
    if check_size is not None:
        check_size(size)
    try:
        return matplotlib.image.imread(path)
    except Exception as err:  # noqa: BLE001 -- any decoder failure of a damaged image
        raise ValueError(f"cannot read {what} {str(path)!r}: {str(err)[:200]}") from None

"""Bad inputs through the steady and the run-in command lines, in-process.

Each case is a malformed or hostile scene, file map, initial face, flag or
output path.  Every one must end in exactly one line ``error: ...`` on
stderr that names the bad key, value or file, with the status of bad input
(2), no traceback, nothing written and every existing file byte-identical.
"""

import dataclasses
import pathlib
import re

import numpy as np
import numpy.lib.format as npy_format
import pytest
from conftest import run_cli, scene_text

import steady.cli.solve as steady_cli
import transient.__main__ as transient_cli
from steady.array_files import PNG_SIGNATURE

PRECIOUS = b"a result someone cares about"

#: The scenes each command starts from: n = 40 (steady) and n = 32 (run-in).
BASE = {"steady": scene_text("steady"), "transient": scene_text("runin")}


def run_command(command, argv, capsys):
    """Exit status, stdout and stderr of the command ``"steady"`` or ``"transient"``."""
    return run_cli(steady_cli if command == "steady" else transient_cli, argv, capsys)


def write(d, name, text):
    path = d / name
    path.write_text(text)
    return path


def header_only(path, shape, descr="<i8"):
    """A .npy file whose header announces ``shape`` but holds no data."""
    with open(path, "wb") as f:
        npy_format.write_array_header_1_0(f, {"descr": descr, "fortran_order": False,
                                             "shape": shape})


def with_key(text, key, value):
    """The scene with ``key = ...`` (the first one) set to ``value`` (TOML text)."""
    new, count = re.subn(rf"^{key} = .*$", f"{key} = {value}", text, count=1, flags=re.M)
    assert count == 1, f"test setup: no key {key!r}"
    return new


def file_map(text, path):
    return re.sub(r"^map = .*$", f'map = {{ kind = "file", path = "{path}" }}', text,
                  count=1, flags=re.M)


def with_section(text, section, body):
    """Replace (or add) a whole section ``[section]``."""
    text = re.sub(rf"^\[{section}\]\n(?:[^\[].*\n)*", "", text, flags=re.M)
    return text + f"[{section}]\n{body}\n"


@dataclasses.dataclass(frozen=True)
class Case:
    """A bad input and the fragment its error line must hold.

    ``make(d, base)`` writes what the case needs into the directory ``d``
    (``base``: the command's good scene text) and returns the arguments;
    ``-o d/out.h5 --force`` is added unless they name an output, or
    ``output`` is False.
    """

    name: str
    make: object
    fragment: str
    commands: tuple = ("steady", "transient")
    output: bool = True
    marks: tuple = ()


def scene(text_of):
    """A case maker writing one scene ``s.toml`` from the base text."""
    def make(d, base):
        return [write(d, "s.toml", text_of(base))]
    return make


def scene_and(prepare, text_of, *flags):
    """A case maker that first prepares files in ``d``, then writes the scene."""
    def make(d, base):
        prepare(d)
        return [write(d, "s.toml", text_of(base)), *flags]
    return make


def argv(*args):
    """A case maker with a good scene and these arguments (``{d}`` is the directory)."""
    def make(d, base):
        return [write(d, "s.toml", base), *(str(a).format(d=d) for a in args)]
    return make


def grey_image(d):
    """A 64 x 64 grey-level micrograph of uniform noise, ``grey.npy``."""
    np.save(d / "grey.npy", np.random.default_rng(3517).random((64, 64)))


def micrograph_map(text, keys):
    """The scene with a micrograph map of ``grey.npy`` and ``keys``."""
    return re.sub(r"^map = .*$", f'map = {{ kind = "micrograph", path = "grey.npy", {keys} }}',
                  text, count=1, flags=re.M)


def png_garbage(d):
    (d / "map.png").write_bytes(b"GIF89a" + bytes(64))


#: A coating of phase 1, 0.3 mm thick, over the scene's map.
LAYERS = '[depth]\nkind = "layers"\n[[depth.layers]]\nthickness = 3e-4\nphase = 1\n'
#: Spheres of phase 1 (radius 0.8 mm) in a matrix of phase 0, 2 mm deep.
SPHERES = ('{ kind = "spheres", radius = 8.0e-4, volume_fraction = 0.3, seed = 2031, '
           'depth = 2.0e-3 }')


def png_signature_only(d):
    """``m.png``: the eight bytes that start every PNG file, and nothing else."""
    (d / "m.png").write_bytes(PNG_SIGNATURE)


def symlink_loop(d, name):
    """``d/name``: a symbolic link to itself, which no lookup can resolve."""
    (d / name).symlink_to(name)
    return d / name


def with_loop(name, *args):
    """A case maker with a good scene, ``d/name`` a loop of links and these arguments."""
    def make(d, base):
        symlink_loop(d, name)
        return [write(d, "s.toml", base), *(str(a).format(d=d) for a in args)]
    return make


#: The cut PNG's message, wherever a PNG is read.
PNG_CUT = "m.png' is not a readable PNG image: it holds only the 8-byte PNG signature"


CASES = [
    # -- the scene file itself
    Case("scene missing", lambda d, base: [d / "nope.toml"], "nope.toml' does not exist"),
    Case("scene a directory", lambda d, base: [d], "is a directory, not a file"),
    Case("scene a device", lambda d, base: ["/dev/zero"], "'/dev/zero' is not a regular file"),
    Case("scene over 1 MiB", scene(lambda t: with_key(t, "coefficients",
                                                      "[" + "1e-9, " * 200_000 + "1e-9]")),
         "is larger than 1 MiB"),
    Case("scene not UTF-8", lambda d, base: [(d / "s.toml", (d / "s.toml").write_bytes(
        base.encode() + b"# \xff\n"))[0]], "is not UTF-8 text"),
    Case("malformed TOML", scene(lambda t: t.replace("[grid]", "[grid")), "malformed TOML"),
    Case("nested 100,000 deep", scene(lambda t: with_key(t, "coefficients",
                                                         "[" * 100_000 + "]" * 100_000)),
         "nested too deeply"),
    # -- values: shortened in the message
    Case("100,000 coefficients", scene(lambda t: with_key(t, "coefficients",
                                                          "[" + "1e-9, " * 99_999 + "1e-9]")),
         "[wear] coefficients has 100000 values [1e-09, 1e-09"),
    Case("900 kB string", scene(lambda t: t.replace("[wear]", '[wear]\nexponent = "'
                                                    + "x" * 900_000 + '"')),
         "[wear] exponent must be a number > 0 (1), got 'xxx"),
    Case("100 kB key", scene(lambda t: t.replace("[grid]", "[grid]\n" + "k" * 100_000 + " = 1")),
         "unknown key 'kkkk"),
    Case("radius a string", scene(lambda t: with_key(t, "radius", '"4 mm"')),
         "[punch] radius must be a number > 0 (m), got '4 mm'"),
    # A TOML date, time or big integer is shown as written, not as Python holds it.
    Case("radius a date", scene(lambda t: with_key(t, "radius", "1979-05-27")),
         "[punch] radius must be a number > 0 (m), got 1979-05-27 (a date)"),
    Case("n a time of day", scene(lambda t: with_key(t, "n", "07:32:00")),
         "[grid] n must be an integer >= 2, got 07:32:00 (a time of day)"),
    Case("coefficients with a date-time", scene(lambda t: with_key(
        t, "coefficients", "[1979-05-27T07:32:00Z, 1e-12]")),
         "[wear] coefficients must be an array of numbers each > 0 (1/Pa), got "
         "[1979-05-27T07:32:00+00:00 (a date-time), 1e-12]"),
    Case("n = 10^30", scene(lambda t: with_key(t, "n", str(10**30))),
         "[grid] n = 1e+30: the pixel h = 2 L / n = 8e-33 m is outside [1e-30, 1e+30] m"),
    Case("n not an integer", scene(lambda t: with_key(t, "n", "32.5")),
         "[grid] n must be an integer >= 2, got 32.5"),
    Case("E_star nan", scene(lambda t: with_key(t, "E_star", "nan")),
         "[counterbody] E_star must be a number > 0 (Pa), got nan"),
    Case("too few coefficients", scene(lambda t: with_key(t, "coefficients", "[1e-9]")),
         "[wear] coefficients has 1 values [1e-09] but the phase map has 2 phases"),
    Case("Voronoi phase off the face", scene(lambda t: with_key(with_key(t, "n", "8"), "map", (
        '{ kind = "voronoi", n_seeds = 2, fill_factors = [0.5, 0.5], seed = 2306 }'))),
         "phase 1 has no pixel on the face with these 2 seeds (seed = 2306) at n = 8"),
    # -- size
    Case("n = 100000", scene(lambda t: with_key(t, "n", "100000")),
         "at n = 100000"),
    Case("n = 2^63 - 1", scene(lambda t: with_key(t, "n", str(2**63 - 1))),
         "[grid] n: grid size n = 9223372036854775807 is larger than 1073741823: an n x n grid "
         "of 8-byte values would exceed the memory a process can address"),
    Case("n = 2^63 - 1, no memory check", lambda d, base: [
        write(d, "s.toml", with_key(base, "n", str(2**63 - 1))), "--memory-limit", "inf"],
         "[grid] n: grid size n = 9223372036854775807 is larger than"),
    Case("n = 12000", lambda d, base: [write(d, "s.toml", with_key(base, "n", "12000")),
                                       "--memory-limit", "16"],
         "GiB may be used (--memory-limit)"),
    Case("--memory-limit tiny", argv("--memory-limit", "0.001"),
         "1.02 MiB may be used (--memory-limit)"),
    Case("--memory-limit not a number", argv("--memory-limit", "lots"),
         "argument --memory-limit: expected a size in GiB, got 'lots'"),
    # A negative number in exponent form is the flag's value, refused by its check.
    Case("--memory-limit -1e-4", argv("--memory-limit", "-1e-4"),
         "argument --memory-limit: expected a positive size in GiB, got '-1e-4'"),
    Case("--depth -1e-4", argv("--depth", "-1e-4"),
         "--depth must be a number >= 0 (m), got -0.0001", ("steady",)),
    Case("--depth -inf", argv("--depth", "-inf"),
         "--depth must be a number >= 0 (m), got -inf", ("steady",)),
    # -- file maps
    Case("map missing", scene(lambda t: file_map(t, "gone.npy")), "gone.npy' does not exist"),
    Case("map a directory", scene_and(lambda d: (d / "dir.npy").mkdir(),
                                      lambda t: file_map(t, "dir.npy")),
         "dir.npy' is a directory, not a file"),
    Case("map a device", scene(lambda t: file_map(t, "/dev/null")),
         "'/dev/null' is not a regular file"),
    Case("map empty", scene_and(lambda d: (d / "m.npy").write_bytes(b""),
                                lambda t: file_map(t, "m.npy")), "m.npy' is empty (0 bytes)"),
    Case("map truncated", scene_and(lambda d: header_only(d / "m.npy", (8, 8)),
                                    lambda t: file_map(t, "m.npy")),
         "m.npy' is truncated: its header announces 8 x 8 values of int64"),
    Case("map claims 100000 x 100000", scene_and(
        lambda d: header_only(d / "m.npy", (100000, 100000)), lambda t: file_map(t, "m.npy")),
         "m.npy' has 100000 x 100000 pixels, more than the grid's n"),
    Case("map not a .npy", scene_and(lambda d: (d / "m.npy").write_text("0 1\n1 0\n"),
                                     lambda t: file_map(t, "m.npy")),
         "m.npy' is not a .npy file"),
    Case("map of floats", scene_and(lambda d: np.save(d / "m.npy", np.zeros((8, 8))),
                                    lambda t: file_map(t, "m.npy")),
         "m.npy' must hold integers, got dtype float64"),
    Case("map PNG garbage", scene_and(png_garbage, lambda t: file_map(t, "map.png")),
         "map.png' is not a PNG image"),
    # -- micrographs: refused before the image is segmented (10 phases would take years)
    Case("micrograph of 10 phases, 2 coefficients", scene_and(
        grey_image, lambda t: micrograph_map(t, "n_phases = 10")),
         "but [phases] map n_phases = 10"),
    Case("micrograph of 10^30 phases", scene_and(
        grey_image, lambda t: micrograph_map(t, f"n_phases = {10**30}")),
         "but [phases] map n_phases = 1e+30"),
    Case("micrograph of 6 phases by Otsu", scene_and(
        grey_image, lambda t: with_key(micrograph_map(t, "n_phases = 6"), "coefficients",
                                       "[1e-13, 2e-13, 3e-13, 4e-13, 5e-13, 6e-13]")),
         "[phases] map: n_phases = 6 by Otsu's thresholds would search C(256, 5) = 8.8e+09 sets"),


    # -- a PNG cut after its signature, everywhere a PNG is read
    Case("map PNG signature only", scene_and(png_signature_only, lambda t: file_map(t, "m.png")),
         "phase map '{d}/" + PNG_CUT),
    Case("micrograph PNG signature only", scene_and(png_signature_only, lambda t: with_key(
        t, "map", '{ kind = "micrograph", path = "m.png", n_phases = 2, pixel_size = 1e-4 }')),
         "micrograph '{d}/" + PNG_CUT),
    Case("mask PNG signature only", scene_and(png_signature_only, lambda t: with_section(
        t, "punch", 'shape = "mask"\npath = "m.png"\npixel_size = 2e-4')),
         "face mask '{d}/" + PNG_CUT),
    # -- a spread of inclusion radii whose distribution overflows
    Case("inclusions radius_spread 1e308", scene(lambda t: with_key(t, "map", (
        '{ kind = "inclusions", radius = 5e-4, seed = 5, fill_factor = 0.2, '
        'radius_spread = 1e308 }'))),
         "[phases] map radius_spread must be a number in [0, 10] (1), got 1e+308"),
    # -- a sphere fraction that places no sphere
    Case("spheres of volume fraction 1e-6", scene(lambda t: with_key(t, "map", (
        '{ kind = "spheres", radius = 8e-4, volume_fraction = 1e-6, seed = 2031, '
        'depth = 2e-3 }'))),
         "sphere volume_fraction = 1e-06 places no sphere of radius 0.0008 m: the particle "
         "phase would have no voxel"),
    # -- loops of symbolic links: refused by whatever opens the file, naming it
    Case("scene a symlink loop", lambda d, base: [symlink_loop(d, "loop.toml")],
         "cannot read scene file '{d}/loop.toml': Too many levels of symbolic links"),
    Case("-o a symlink loop", with_loop("loop.h5", "-o", "{d}/loop.h5", "--force"),
         "output '{d}/loop.h5': Too many levels of symbolic links"),
    Case("--plot a symlink loop", with_loop("loop.png", "--plot", "{d}/loop.png"),
         "--plot '{d}/loop.png': Too many levels of symbolic links"),
    Case("map a symlink loop", scene_and(lambda d: symlink_loop(d, "m.npy"),
                                         lambda t: file_map(t, "m.npy")),
         "cannot read phase map '{d}/m.npy': Too many levels of symbolic links"),
    # -- output paths
    Case("no -o", lambda d, base: [write(d, "s.toml", base)], "the following arguments are "
                                                              "required: -o/--output",
         output=False),
    Case("-o a directory", argv("-o", "{d}", "--force"), "is a directory"),
    Case("-o a device", argv("-o", "/dev/null", "--force"), "'/dev/null' is not a regular file"),
    Case("-o below a file", argv("-o", "{d}/s.toml/x.h5"), "s.toml' is a file, not a directory"),
    Case("-o unwritable", argv("-o", "/proc/runin-out.h5"), "cannot write into '/proc'"),
    Case("-o exists", argv("-o", "{d}/out.h5"), "out.h5' exists"),
    Case("--plot is -o", argv("-o", "{d}/out.h5", "--plot", "{d}/out.h5", "--force"),
         "out.h5'"),
    Case("--plot a directory", argv("--plot", "{d}", "--force"), "--plot"),
    Case("unknown flag", argv("--fast"), "unrecognized arguments: --fast"),
    # -- the run-in's own sections and flags
    Case("[transient] unknown key", scene(lambda t: with_section(t, "transient", "bogus = 1")),
         "unknown key 'bogus' in [transient]", ("transient",)),
    Case("[transient] scheme", scene(lambda t: with_section(t, "transient", 'scheme = "rk4"')),
         "unknown scheme 'rk4'", ("transient",)),
    Case("[transient] snapshots_s_star", scene(lambda t: with_section(
        t, "transient", 'snapshots_s_star = "often"')),
         "[transient] snapshots_s_star must be an array of numbers each >= 0 (s*), got 'often'",
         ("transient",)),
    # A distance that was in s* under its old name is refused, its value given in m (s* =
    # 0.004 / (1e-13 1.3e6) m = 30769.2 m for this scene).
    Case("[transient] snapshots in s*", scene(lambda t: with_section(
        t, "transient", "snapshots = [0.1, 1]")),
         "[transient] snapshots was a distance in units of s*; distances are now in m: "
         "snapshot_distances ([0.1, 1] s* with this scene's s* = 30769.2 m is "
         "snapshot_distances = [3076.92, 30769.2]), or snapshots_s_star = [0.1, 1] to keep "
         "them in s*", ("transient",)),
    Case("[transient] max_distance in s*", scene(lambda t: with_section(
        t, "transient", "max_distance = 2.0")),
         "distances are now in m: distance_limit (2.0 s* with this scene's s* = 30769.2 m is "
         "distance_limit = 61538.5)", ("transient",)),
    Case("[transient] max_steps", scene(lambda t: with_section(t, "transient", "max_steps = 0")),
         "[transient] max_steps must be an integer >= 1, got 0", ("transient",)),
    Case("[transient] contact_rtol", scene(lambda t: with_section(t, "transient",
                                                                  "contact_rtol = 0.0")),
         "[transient] contact_rtol must be a number in (0, 1) (1), got 0.0", ("transient",)),
    Case("100,000 snapshots", scene(lambda t: with_key(with_section(
        t, "transient", "snapshots_s_star = [" + ", ".join(f"{i}.0" for i in range(100_000))
        + "]"),
        "n", "256")), "a run-in at n = 256 with 100000 snapshots needs about", ("transient",)),
    # -- a run-in across interfaces needs a law k_i g(p); a section is any steady problem
    Case("threshold law over [depth]", scene(lambda t: t.replace(
        "[wear]", '[wear]\nlaw = "threshold"\nthresholds = [0.0, 0.0]') + LAYERS),
         "[wear] law = 'threshold' and [depth]: a run-in across the interfaces of phases that "
         "change with depth needs a law k_i g(p) ([wear] law = 'archard' or 'power')",
         ("transient",)),
    Case("table law on spheres", scene(lambda t: with_key(with_key(
        t.replace("coefficients = ", "pressures = [[0, 1e5], [0, 1e5]]\nrates = "), "rates",
        "[[0, 1e-8], [0, 1e-9]]"), "map", SPHERES).replace("[wear]", '[wear]\nlaw = "table"')),
         "[wear] law = 'table' and [phases] map kind = 'spheres': a run-in across the "
         "interfaces", ("transient",)),
    Case("[initial_face] missing file", scene(lambda t: with_section(
        t, "initial_face", 'kind = "file"\npath = "h.npy"')), "h.npy' does not exist",
        ("transient",)),
    Case("[initial_face] empty file", scene_and(
        lambda d: (d / "h.npy").write_bytes(b""),
        lambda t: with_section(t, "initial_face", 'kind = "file"\npath = "h.npy"')),
         "initial face file", ("transient",)),
    Case("[initial_face] wrong shape", scene_and(
        lambda d: np.save(d / "h.npy", np.zeros((8, 8))),
        lambda t: with_section(t, "initial_face", 'kind = "file"\npath = "h.npy"')),
         "h.npy' holds an array of shape (8, 8); (32, 32) is needed", ("transient",)),
    Case("[initial_face] NaN on the face", scene_and(
        lambda d: np.save(d / "h.npy", np.full((32, 32), np.nan)),
        lambda t: with_section(t, "initial_face", 'kind = "file"\npath = "h.npy"')),
         "h.npy': recession field must be finite on the face, got ", ("transient",)),
    # -- every array read from a file refuses complex numbers (numpy would keep the real part)
    Case("[initial_face] complex file", scene_and(
        lambda d: np.save(d / "h.npy", np.zeros((32, 32)) * (1 + 1e-6j)),
        lambda t: with_section(t, "initial_face", 'kind = "file"\npath = "h.npy"')),
         "h.npy' holds complex numbers (complex128); it must hold real numbers", ("transient",)),
    Case("[initial_face] boolean file", scene_and(
        lambda d: np.save(d / "h.npy", np.zeros((32, 32), dtype=bool)),
        lambda t: with_section(t, "initial_face", 'kind = "file"\npath = "h.npy"')),
         "h.npy' holds booleans (bool); it must hold real numbers", ("transient",)),
    Case("map of complex numbers", scene_and(
        lambda d: np.save(d / "m.npy", np.zeros((8, 8), dtype=complex)),
        lambda t: file_map(t, "m.npy")),
         "m.npy' holds complex numbers (complex128); it must hold integers"),
    Case("mask of complex numbers", scene_and(
        lambda d: np.save(d / "m.npy", np.ones((8, 8), dtype=complex)),
        lambda t: t.replace("radius = 0.004",
                            'shape = "mask"\npath = "m.npy"\npixel_size = 1e-3')),
         "m.npy' holds complex numbers (complex128); it must hold booleans (True on the face) "
         "or integers"),
    Case("voxels of complex numbers", scene_and(
        lambda d: np.save(d / "v.npy", np.zeros((8, 8, 2), dtype=complex)),
        lambda t: with_key(t, "map", '{ kind = "voxels", file = "v.npy", voxel_depth = 1e-4 }')),
         "v.npy' holds complex numbers (complex128); it must hold integers"),
    Case("micrograph of complex numbers", scene_and(
        lambda d: np.save(d / "g.npy", np.zeros((64, 64), dtype=complex)),
        lambda t: with_key(t, "map", '{ kind = "micrograph", path = "g.npy", n_phases = 2, '
                                     'pixel_size = 1e-4 }')),
         "g.npy' holds complex numbers (complex128); it must hold real numbers or booleans"),
    Case("[initial_face] angle", scene(lambda t: with_section(
        t, "initial_face", 'kind = "tilted"\nangle = 2.0')),
         "[initial_face] angle must be a number in [0, 1.5708) (rad), got 2.0", ("transient",)),
    Case("[initial_face] kind", scene(lambda t: with_section(t, "initial_face",
                                                             'kind = "wavy"')),
         "kind must be one of", ("transient",)),
    Case("first solve: contact_rtol 1e-300", scene(lambda t: with_section(
        t, "transient", "contact_rtol = 1e-300")),
         "the first contact solve failed: [transient] contact_rtol = 1e-300 is below what "
         "round-off allows", ("transient",)),
    Case("first solve: a 1e300 pixel", scene_and(
        lambda d: np.save(d / "h.npy", np.where(np.arange(32 * 32).reshape(32, 32) == 528,
                                                1e300, 0.0)),
        lambda t: with_section(t, "initial_face", 'kind = "file"\npath = "h.npy"')),
         "the first contact solve failed: the [initial_face] (kind 'file') has a relief of "
         "1e+300 m", ("transient",),
         # The command logs numpy's overflow warning (shown with -v); here it must not raise.
         marks=(pytest.mark.filterwarnings("ignore::RuntimeWarning"),)),
    Case("--tol negative", argv("--tol", "-3"),
         "argument --tol: expected a number in (2.22045e-16, 1] (f*), got '-3'", ("transient",)),
    Case("--tol -1e-4", argv("--tol", "-1e-4"),
         "argument --tol: expected a number in (2.22045e-16, 1] (f*), got '-1e-4'", ("transient",)),
    # A tolerance below the precision of a double (its product with f* underflowed to 0).
    Case("[transient] tol 5e-324", scene(lambda t: with_key(t, "tol", "5e-324")),
         "[transient] tol must be a number in (2.22045e-16, 1] (f*), got 5e-324", ("transient",)),
    Case("--distance-limit -1E+3", argv("--distance-limit", "-1E+3"),
         "argument --distance-limit: expected a number > 0 (m), got '-1E+3'", ("transient",)),
    Case("--max-steps 0", argv("--max-steps", "0"),
         "argument --max-steps: expected an integer >= 1, got '0'", ("transient",)),
    Case("--checkpoint-interval -1", argv("--checkpoint-interval", "-1"),
         "argument --checkpoint-interval: expected a number >= 0 (s), got '-1'", ("transient",)),
    Case("--scheme rk4", argv("--scheme", "rk4"), "argument --scheme: invalid choice: 'rk4'",
         ("transient",)),
    Case("--resume with --force", argv("--resume", "--force"),
         "argument --force: not allowed with argument --resume", ("transient",)),
    Case("--plot is the backup", argv("--plot", "{d}/out.h5.prev", "--force"),
         "--plot and the run file's backup name the same file", ("transient",)),
    Case("-o is the scene", argv("-o", "{d}/s.toml", "--force"),
         "-o and the scene name the same file"),
]

#: Fragments that differ between the commands.
FRAGMENTS = {
    ("n = 100000", "steady"): "a steady solve at n = 100000 needs about",
    ("n = 100000", "transient"): "a run-in at n = 100000 with 2 snapshots needs about",
    ("-o exists", "steady"): "out.h5' exists (use --force to overwrite)",
    ("-o exists", "transient"): "out.h5' exists; use --resume to continue it or --force",
    ("--plot is -o", "steady"): "--plot and -o name the same file",
    ("--plot is -o", "transient"): "--plot and -o name the same file",
}


def _params():
    for case in CASES:
        for command in case.commands:
            yield pytest.param(case, command, id=f"{command}: {case.name}", marks=case.marks)


@pytest.mark.parametrize("case, command", list(_params()))
def test_bad_input_is_one_line_and_status_2(tmp_path, capsys, case, command):
    d = tmp_path / "case"
    d.mkdir()
    (d / "out.h5").write_bytes(PRECIOUS)
    args = case.make(d, BASE[command])
    if case.output and "-o" not in args:
        args += ["-o", d / "out.h5"]
        if "--force" not in args and "--resume" not in args:
            args.append("--force")
    before = {p.name: p.read_bytes() for p in d.iterdir() if p.is_file()}
    status, out, err = run_command(command, args, capsys)
    fragment = FRAGMENTS.get((case.name, command), case.fragment).replace("{d}", str(d))
    lines = err.splitlines()
    assert "Traceback" not in err, f"traceback on stderr: {err[-2000:]}"
    assert status == 2, f"exit {status}, stderr {err[:500]!r}"
    assert len(lines) == 1 and lines[0].startswith("error: "), \
        f"expected one 'error:' line, got {len(lines)}: {err[:1000]!r}"
    assert fragment in lines[0], f"{lines[0][:500]!r} lacks {fragment!r}"
    assert len(lines[0]) < 500, f"error line of {len(lines[0])} characters"
    assert out == "", f"stdout after a refusal: {out[:200]!r}"
    after = {p.name: p.read_bytes() for p in d.iterdir() if p.is_file()}
    assert after == before, \
        f"files changed: {sorted(set(after) ^ set(before))} or contents of {sorted(before)}"


def test_every_case_names_what_is_bad():
    """The table covers every class of the bad-input list at least once per command."""
    names = {c.name for c in CASES}
    assert len(names) == len(CASES), "case names must be unique"
    per_command = {cmd: sum(cmd in c.commands for c in CASES) for cmd in BASE}
    assert per_command["steady"] >= 35 and per_command["transient"] >= 50, per_command


def test_memory_override_lets_a_scene_run(tmp_path, capsys):
    """``--memory-limit inf`` skips the check; a scene that fits runs as before."""
    (tmp_path / "s.toml").write_text(BASE["steady"])
    status, out, err = run_command("steady", [tmp_path / "s.toml", "-o", tmp_path / "r.h5",
                                          "--memory-limit", "inf", "--no-slope-error"], capsys)
    assert status == 0 and err == "", f"exit {status}: {err!r}"
    assert "rms / grad_f0" in out, f"summary {out!r}"
    assert pathlib.Path(tmp_path / "r.h5").is_file(), "result written"


@pytest.mark.parametrize("law", ['law = "threshold"\nthresholds = [0.0, 1e3]\n'
                                 'coefficients = [1e-13, 1e-12]',
                                 'law = "table"\npressures = [[0, 1e5], [0, 1e5]]\n'
                                 'rates = [[0, 1e-8], [0, 1e-9]]'])
def test_runin_steady_solves_a_section_under_any_law(tmp_path, capsys, law):
    text = re.sub(r"^coefficients = .*$", law, BASE["steady"], count=1, flags=re.M)
    path = write(tmp_path, "s.toml", text + LAYERS)
    status, out, err = run_command("steady", [path, "-o", tmp_path / "r.h5", "--depth", "4e-4",
                                              "--no-slope-error"], capsys)
    assert status == 0 and "error" not in err, f"exit {status}: {err!r}"
    assert "0.0004 m below the initial surface" in out, out


# -- a missing file from Python ----------------------------------------------
def _loaders():
    from steady.design import DesignTable
    from steady.fit_files import read_fit, read_measured
    from steady.output import read_result
    from steady.scene import load_scene
    from steady.sweep import SweepFile
    from transient.output import read_run
    from transient.scene import load_transient_scene

    return [("scene file", load_scene, {}), ("scene file", load_transient_scene, {}),
            ("result file", read_result, {}), ("run file", read_run, {}),
            ("fit file", read_fit, {}), ("measured map", read_measured, {"pixel_size": 1e-4}),
            ("design table", DesignTable.read, {}), ("sweep file", SweepFile, {})]


@pytest.mark.parametrize("what, read, kwargs", _loaders(),
                         ids=lambda v: getattr(v, "__qualname__", None))
def test_a_missing_file_is_file_not_found_from_python(tmp_path, what, read, kwargs):
    """Python's own exception for a file that does not exist, with the file named."""
    path = tmp_path / "nowhere.h5"
    with pytest.raises(FileNotFoundError) as err:
        read(path, **kwargs)
    assert str(err.value).startswith(f"{what} {str(path)!r} does not exist"), str(err.value)
    (tmp_path / "a_directory.h5").mkdir()
    with pytest.raises(ValueError, match="a_directory.h5"):  # there, but not a file: bad input
        read(tmp_path / "a_directory.h5", **kwargs)


def test_a_missing_map_named_by_a_scene_is_a_bad_value(tmp_path):
    """A file the scene names is one of its values: ValueError naming the key and the file."""
    from steady.scene import load_scene

    path = write(tmp_path, "s.toml", file_map(BASE["steady"], "gone.npy"))
    with pytest.raises(ValueError) as err:
        load_scene(path)
    assert "[phases] map" in str(err.value) and "gone.npy' does not exist" in str(err.value), \
        str(err.value)

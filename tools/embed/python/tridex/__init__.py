"""tridex: a milling session in Python (docs/embedding.md).

A stock and a tool table; a program fed in pieces as it comes, each piece cut as it is read;
questions about the stock as it stands. The same solid as `tridex simulate` on the same program,
stock, tools and --dexel-cell.

    import tridex
    s = tridex.Session(stock=(0, 0, -20, 100, 80, 0), tools="tools.json", cell=0.5)
    s.feed("G21 G90 T1 M6 S10000 M3\\nG0 X-10 Y10 Z5\\nG1 Z-2 F800\\nG1 X110\\n")
    print(s.removed_volume(), s.would_cut("G1 Y20"), s.inside((50, 10, -1)))
    s.write_stl("part.stl")

A thin layer over the C API (tridex.h) with ctypes: no compiled Python extension, so the module
works with any Python 3 and needs nothing but the library beside it.
"""

import ctypes
import os

__all__ = ["Session", "TridexError", "BadInput", "version"]

_HERE = os.path.dirname(os.path.abspath(__file__))


def _load():
    names = ["libtridex_c.so", "libtridex_c.so.0"]
    # Beside this file in the build folder; in the installed layout, PREFIX/lib/libtridex_c.so.0
    # three levels up from PREFIX/lib/python3/dist-packages/tridex.
    for folder in (_HERE, os.path.join(_HERE, "..", "..", "..")):
        for name in names:
            path = os.path.join(folder, name)
            if os.path.exists(path):
                return ctypes.CDLL(path)
    # An installed package may sit apart from the library: the loader's search path.
    return ctypes.CDLL("libtridex_c.so.0")


_lib = _load()


class _Options(ctypes.Structure):
    _fields_ = [
        ("stock", ctypes.c_double * 6),
        ("tools", ctypes.c_char_p),
        ("machine", ctypes.c_char_p),
        ("cell", ctypes.c_double),
        ("threads", ctypes.c_uint),
        ("stock_file", ctypes.c_char_p),
    ]


_P = ctypes.c_void_p
_lib.tridex_last_error.restype = ctypes.c_char_p
_lib.tridex_version.restype = ctypes.c_char_p
_lib.tridex_session_new.argtypes = [ctypes.POINTER(_Options), ctypes.POINTER(_P)]
_lib.tridex_session_free.argtypes = [_P]
_lib.tridex_session_free.restype = None
_lib.tridex_session_feed.argtypes = [_P, ctypes.c_char_p]
_lib.tridex_session_feed_measured.argtypes = [_P, ctypes.c_char_p, ctypes.POINTER(ctypes.c_double)]
_lib.tridex_session_add_move.argtypes = [_P, ctypes.c_double * 3, ctypes.c_double * 3, ctypes.c_int,
                                         ctypes.c_double * 3, ctypes.c_int]
_lib.tridex_session_extent.argtypes = [_P, ctypes.c_double * 3, ctypes.c_double * 3,
                                       ctypes.POINTER(ctypes.c_double), ctypes.c_int,
                                       ctypes.POINTER(ctypes.c_int)]
_lib.tridex_session_removed_volume.argtypes = [_P, ctypes.POINTER(ctypes.c_double)]
_lib.tridex_session_would_cut.argtypes = [_P, ctypes.c_char_p, ctypes.POINTER(ctypes.c_double)]
_lib.tridex_session_inside.argtypes = [_P, ctypes.c_double * 3, ctypes.POINTER(ctypes.c_int)]
_lib.tridex_session_write_stl.argtypes = [_P, ctypes.c_char_p]
_lib.tridex_session_moves.argtypes = [_P, ctypes.POINTER(ctypes.c_longlong)]
_lib.tridex_session_warning_count.argtypes = [_P, ctypes.POINTER(ctypes.c_int)]
_lib.tridex_session_warning.argtypes = [_P, ctypes.c_int]
_lib.tridex_session_warning.restype = ctypes.c_char_p


class TridexError(Exception):
    """A call failed; `status` is the C API's (1: failure, 2: bad input, 3: bad call)."""

    def __init__(self, status, message):
        super().__init__(message)
        self.status = status


class BadInput(TridexError, ValueError):
    """Bad G-code, a tool missing from the table, a bad stock or option (status 2)."""


def _check(status):
    if status != 0:
        message = _lib.tridex_last_error().decode("utf-8", "replace")
        raise (BadInput if status == 2 else TridexError)(status, message)


def _text(value, what):
    if isinstance(value, bytes):
        return value
    if not isinstance(value, str):
        raise TypeError(what + " must be str")
    return value.encode("utf-8")


def _path(value):
    return os.fsencode(value)


def _point(value, what):
    values = [float(v) for v in value]
    if len(values) != 3:
        raise ValueError(what + " must be (x, y, z)")
    return (ctypes.c_double * 3)(*values)


def version():
    return _lib.tridex_version().decode()


class Session:
    """A stock being milled: feed() program text, then ask about the stock."""

    def __init__(self, stock, tools=None, machine=None, cell=0.0, threads=0):
        options = _Options()
        if isinstance(stock, (str, bytes, os.PathLike)):  # a closed STL
            options.stock_file = _path(stock)
        else:
            box = [float(v) for v in stock]
            if len(box) != 6:
                raise ValueError("stock must be (xmin, ymin, zmin, xmax, ymax, zmax) or an STL file")
            options.stock = (ctypes.c_double * 6)(*box)
        options.tools = _path(tools) if tools is not None else None
        options.machine = _path(machine) if machine is not None else None
        options.cell = float(cell)
        options.threads = int(threads)
        handle = _P()
        self._handle = None
        _check(_lib.tridex_session_new(ctypes.byref(options), ctypes.byref(handle)))
        self._handle = handle

    def close(self):
        if self._handle:
            _lib.tridex_session_free(self._handle)
            self._handle = None

    def __del__(self):
        self.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def _h(self):
        if not self._handle:
            raise TridexError(3, "the session is closed")
        return self._handle

    def feed(self, text):
        """Runs more program text (state kept from the last piece); its moves are cut."""
        _check(_lib.tridex_session_feed(self._h(), _text(text, "text")))

    def feed_measured(self, text):
        """feed(), returning the mm^3 that piece removed (costs a question before and after)."""
        out = ctypes.c_double()
        _check(_lib.tridex_session_feed_measured(self._h(), _text(text, "text"),
                                                 ctypes.byref(out)))
        return out.value

    def add_move(self, start, end, tool, axis=(0, 0, 1), rapid=False):
        """One straight move given directly: tool tip from start to end (mm, the part's
        coordinates, as the stock), cut by `tool` of the table, spindle along `axis`."""
        _check(_lib.tridex_session_add_move(self._h(), _point(start, "start"), _point(end, "end"),
                                            int(tool), _point(axis, "axis"), 1 if rapid else 0))

    def extent(self, point, direction=(0, 0, 1)):
        """The intervals (t_in, t_out) of the line point + t*direction (t in mm along the unit
        direction) inside the stock as it stands, ascending."""
        count = ctypes.c_int()
        capacity = 16
        while True:
            spans = (ctypes.c_double * (2 * capacity))()
            _check(_lib.tridex_session_extent(self._h(), _point(point, "point"),
                                              _point(direction, "direction"), spans, capacity,
                                              ctypes.byref(count)))
            if count.value <= capacity:
                return [(spans[2 * k], spans[2 * k + 1]) for k in range(count.value)]
            capacity = count.value

    def height(self, x, y):
        """The stock's top at (x, y) along +z, or None where no stock is left."""
        spans = self.extent((x, y, 0), (0, 0, 1))
        return spans[-1][1] if spans else None

    def removed_volume(self):
        """mm^3 removed so far."""
        out = ctypes.c_double()
        _check(_lib.tridex_session_removed_volume(self._h(), ctypes.byref(out)))
        return out.value

    def would_cut(self, block):
        """Depth (mm) the block would cut into the stock as it stands, else 0; cuts nothing."""
        out = ctypes.c_double()
        _check(_lib.tridex_session_would_cut(self._h(), _text(block, "block"), ctypes.byref(out)))
        return out.value

    def inside(self, point):
        """Whether point (x, y, z) lies inside the stock as it stands."""
        x, y, z = (float(v) for v in point)
        out = ctypes.c_int()
        _check(_lib.tridex_session_inside(self._h(), (ctypes.c_double * 3)(x, y, z),
                                          ctypes.byref(out)))
        return bool(out.value)

    def write_stl(self, path):
        """Writes the solid as binary STL."""
        _check(_lib.tridex_session_write_stl(self._h(), _path(path)))

    def moves(self):
        out = ctypes.c_longlong()
        _check(_lib.tridex_session_moves(self._h(), ctypes.byref(out)))
        return out.value

    def warnings(self):
        count = ctypes.c_int()
        _check(_lib.tridex_session_warning_count(self._h(), ctypes.byref(count)))
        return [_lib.tridex_session_warning(self._h(), k).decode("utf-8", "replace")
                for k in range(count.value)]

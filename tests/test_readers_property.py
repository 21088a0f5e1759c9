"""Property tests of every reader (issue 24): bad input never becomes a wrong result.

Each input is either read exactly as its format specifies (compared with a value the
test computes on its own, from the values it wrote) or rejected with ``InputError``;
never another exception, never a silent misread. Inputs are valid records, or valid
records with one mutation (a field dropped, added, duplicated or replaced; a row or
bytes cut or added; a header value broken).

Runs derandomized (profile ``ci`` of ``tests/conftest.py``: the same examples on every
run, no example database) unless ``FLOORSCAN_HYPOTHESIS_PROFILE=dev`` asks for fresh ones.
"""

from __future__ import annotations

import math
import re
import struct
from types import SimpleNamespace

import numpy as np
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st

from floorscan.core.io import InputError



@pytest.fixture(scope="module")
def workdir(tmp_path_factory):
    return tmp_path_factory.mktemp("property")


# --- CARMEN lines ------------------------------------------------------------------------

#: Tokens a mutation puts into a line: numbers, non-finite values, words, Python-only forms.
TOKENS = st.sampled_from(["0", "1", "3", "-1", "2.5", "1e3", "nan", "inf", "-inf", "abc", "1_0", "0x10", "", "+4"])


def _num(draw, finite_only=False):
    """A float and how a log writer might print it."""
    special = [] if finite_only else [math.nan, math.inf, -math.inf]
    v = draw(st.one_of(st.floats(-1e6, 1e6, allow_nan=False), st.sampled_from([0.0, -0.0, 81.91, 1e-9, *special])))
    fmt = draw(st.sampled_from(["repr", "%.3f", "%g"]))
    text = repr(v) if fmt == "repr" else fmt % v
    return float(text), text


@st.composite
def carmen_lines(draw):
    """(tokens of a valid FLASER or ROBOTLASER1 line, then maybe one mutation)."""
    kind = draw(st.sampled_from(["FLASER", "ROBOTLASER1"]))
    n = draw(st.integers(1, 12))
    ranges = [draw(st.one_of(st.sampled_from(["nan", "inf", "-1.0", "0", "49.999", "50.0", "81.91"]),
                             st.floats(0.01, 60, allow_nan=False).map(lambda v: "%.3f" % v)))
              for _ in range(n)]
    pose = [_num(draw, finite_only=True)[1] for _ in range(3)]
    stamp = draw(st.one_of(st.floats(0, 9e9).map(lambda v: "%.6f" % v), st.sampled_from(["0", "1e9", "0.000"])))
    host = draw(st.sampled_from(["pippo", "nohost", "robot_1", "1.5"]))
    if kind == "FLASER":
        tok = ["FLASER", str(n), *ranges, *pose, *[_num(draw)[1] for _ in range(3)], stamp, host, stamp]
    else:
        m = draw(st.integers(0, 3))
        start = _num(draw, finite_only=True)[1]
        res = "%.5f" % draw(st.floats(-0.1, 0.1))
        rmax = draw(st.sampled_from(["30.0", "0", "-1", "81.9", "49.5"]))
        tok = (["ROBOTLASER1", "0", start, "3.1416", res, rmax, "0.01", "0", str(n), *ranges, str(m)]
               + ["%.1f" % draw(st.floats(0, 100)) for _ in range(m)]
               + pose + [_num(draw)[1] for _ in range(8)] + [stamp, host, stamp])
    op = draw(st.sampled_from(["none", "none", "drop", "insert", "duplicate", "replace"]))
    if op != "none":
        i = draw(st.integers(1, len(tok) - (op != "insert")))
        if op == "drop":
            del tok[i]
        elif op == "insert":
            tok.insert(i, draw(TOKENS))
        elif op == "duplicate":
            tok.insert(i, tok[i])
        else:
            tok[i] = draw(TOKENS)
    return [t for t in tok if t != ""]


def carmen_expected(tok, fov=math.pi, max_range_m=50.0):
    """The values of a line read field by field as the CARMEN layout says, or None when
    the line breaks it. Written apart from the reader: it walks the fields in order."""

    fields = iter(tok[1:])

    def take():
        return next(fields)

    def number():
        t = take()
        if "_" in t:
            raise ValueError(t)
        return float(t)

    def count(minimum):
        t = take()
        if not re.fullmatch(r"\+?[0-9]+", t) or int(t) < minimum:
            raise ValueError(t)
        return int(t)

    try:
        if tok[0] == "FLASER":
            n = count(1)
            ranges = [number() for _ in range(n)]
            pose = [number() for _ in range(3)]
            [number() for _ in range(3)]
            t_s = number()
            take()
            number()
            start, inc, rmax = -fov / 2, (fov / (n - 1) if n % 2 and n > 1 else fov / n), math.inf
            limits_ok = True
        else:
            number()
            start, _, inc, line_max, _, _ = (number() for _ in range(6))
            n = count(1)
            ranges = [number() for _ in range(n)]
            m = count(0)
            [number() for _ in range(m)]
            pose = [number() for _ in range(3)]
            [number() for _ in range(8)]
            t_s = number()
            take()
            number()
            limits_ok = all(map(math.isfinite, (start, inc, line_max)))
            rmax = line_max if line_max > 0 else math.inf
        if next(fields, None) is not None:
            return None
    except (StopIteration, ValueError):
        return None
    # the stamp may be any number: the test's log holds one laser line, so a stamp out of
    # range is more than half of the log's, junk, and the reader keeps the line with its
    # stamp as written and makes the stamps up (floorscan.ingest.carmen_stamps.stamp_class)
    if not (limits_ok and all(map(math.isfinite, pose))):
        return None
    rmax = min(rmax, max_range_m)
    pts = [(r * math.cos(start + inc * i), r * math.sin(start + inc * i))
           for i, r in enumerate(ranges) if math.isfinite(r) and 1e-9 <= r < rmax]
    return {"t_s": t_s, "pose": pose, "points": np.array(pts, dtype=np.float32).reshape(-1, 2), "n": n}


def _read_carmen_line(workdir, tok):
    from floorscan.ingest.carmen import parse_carmen

    path = workdir / "line.log"
    path.write_text("# a comment\n" + " ".join(tok) + "\n")
    return parse_carmen(path, max_range_m=50.0)[0][0]


@settings(max_examples=400)
@given(tok=carmen_lines())
# stamps out of range in a log of one line: junk, the line read with its stamp as written
@example(tok=["FLASER", "2", "1.500", "nan", "0.0", "0.0", "0.0", "0", "0", "0", "-1", "pippo", "0.000000"])
@example(tok=["ROBOTLASER1", "0", "0.0", "3.1416", "0.00000", "30.0", "0.01", "0", "2", "nan", "2.000", "0",
              "0.0", "0.0", "0.0", *["0.0"] * 8, "nan", "pippo", "0.000000"])
def test_carmen_line_read_exactly_or_rejected(workdir, tok):
    expected = carmen_expected(tok)
    if expected is None:
        with pytest.raises(InputError, match=r"line.log:2: malformed (FLASER|ROBOTLASER1) line"):
            _read_carmen_line(workdir, tok)
        return
    scan = _read_carmen_line(workdir, tok)
    assert scan["t_s"] == expected["t_s"] or math.isnan(scan["t_s"]) and math.isnan(expected["t_s"])
    assert scan["pose"].tolist() == expected["pose"]
    assert len(scan["points"]) + scan["n_dropped"] == expected["n"]
    np.testing.assert_allclose(scan["points"][:, :2], expected["points"], rtol=1e-6, atol=1e-6)


def carmen_fuzz(workdir, n_lines: int, seed: int) -> dict[str, int]:
    """Mutate valid lines (a field dropped, added or duplicated) and count what the reader
    does with them: ``accepted`` and, of those, ``misread`` (values other than the
    field-by-field reading, or read from a line that breaks the layout); ``crashed``
    (another exception than InputError)."""
    rng = np.random.default_rng(seed)
    out = {"lines": n_lines, "accepted": 0, "misread": 0, "crashed": 0}
    for _ in range(n_lines):
        n = int(rng.integers(1, 9))
        r = [f"{v:.3f}" for v in rng.uniform(0.1, 20, n)]
        p = [f"{v:.4f}" for v in rng.uniform(-50, 50, 6)]
        t = f"{rng.uniform(1e9, 1.7e9):.6f}"
        if rng.random() < 0.5:
            tok = ["FLASER", str(n), *r, *p, t, "host", t]
        else:
            m = int(rng.integers(0, 3))
            tok = (["ROBOTLASER1", "0", "-1.5708", "3.1416", "0.0175", "30.0", "0.01", "0", str(n), *r, str(m)]
                   + [f"{v:.1f}" for v in rng.uniform(0, 100, m)] + p
                   + ["0.1", "0.0", "0.5", "0.3", "0.2", t, "host", t])
        op = rng.integers(3)
        i = int(rng.integers(1, len(tok) + (op == 1)))
        if op == 0:
            del tok[i]
        elif op == 1:
            tok.insert(i, f"{rng.uniform(0, 10):.3f}")
        else:
            tok.insert(i, tok[i])
        try:
            scan = _read_carmen_line(workdir, tok)
        except InputError:
            continue
        except Exception:
            out["crashed"] += 1
            continue
        out["accepted"] += 1
        exp = carmen_expected(tok)
        if exp is None or scan["pose"].tolist() != exp["pose"] or scan["t_s"] != exp["t_s"]:
            out["misread"] += 1
    return out


@pytest.mark.slow
def test_carmen_fuzzed_lines_never_misread(workdir):
    # before issue 24: 2450 of these 4000 lines were accepted, every one of them breaking
    # its layout (fields read from shifted positions)
    got = carmen_fuzz(workdir, 4000, seed=24)
    assert (got["misread"], got["crashed"]) == (0, 0), got


# --- LaserScan and PointCloud2 arrays ----------------------------------------------------


def _maybe_non_finite(strategy):
    return st.one_of(strategy, strategy, strategy, strategy, st.sampled_from([math.nan, math.inf, -math.inf]))


@settings(max_examples=300)
@given(
    ranges=st.lists(st.one_of(st.floats(-1, 40, width=32), st.sampled_from([0.0, 30.0, math.nan, math.inf, -math.inf])),
                    max_size=40),
    angle_min=_maybe_non_finite(st.floats(-4, 4, width=32)),
    angle_increment=_maybe_non_finite(st.floats(-0.125, 0.125, width=32)),
    range_min=_maybe_non_finite(st.floats(0, 1, width=32)),
    range_max=_maybe_non_finite(st.floats(1, 100, width=32)),
    limits=st.tuples(st.one_of(st.none(), st.floats(0, 2)), st.one_of(st.none(), st.floats(2, 50))),
)
def test_laser_scan_read_exactly_or_rejected(ranges, angle_min, angle_increment, range_min, range_max, limits):
    from floorscan.ingest.ros_messages import laser_scan_xyz

    msg = SimpleNamespace(angle_min=angle_min, angle_increment=angle_increment, range_min=range_min,
                          range_max=range_max, ranges=np.array(ranges, dtype=np.float32))
    header = dict(angle_min=angle_min, angle_increment=angle_increment, range_min=range_min, range_max=range_max)
    bad = [k for k, v in header.items() if not math.isfinite(v)]
    if bad:
        with pytest.raises(InputError, match=rf"s.bag: '/scan' message 7 \(t 5 ns\): LaserScan {bad[0]} is "):
            laser_scan_xyz(msg, "s.bag", "/scan", 7, 5, *limits)
        return
    pts, dropped = laser_scan_xyz(msg, "s.bag", "/scan", 7, 5, *limits)
    lo = max(range_min, 0.0 if limits[0] is None else limits[0])
    hi = min(range_max, math.inf if limits[1] is None else limits[1])
    want = [(r * math.cos(angle_min + angle_increment * i), r * math.sin(angle_min + angle_increment * i), 0.0)
            for i, r in enumerate(float(v) for v in np.float32(ranges)) if math.isfinite(r) and lo <= r < hi]
    assert dropped == len(ranges) - len(want)
    assert pts.dtype == np.float32
    np.testing.assert_allclose(pts, np.array(want, dtype=np.float32).reshape(-1, 3), rtol=1e-6, atol=1e-5)


PC2_TYPES = {"f4": (7, 4), "f8": (8, 8), "u2": (4, 2), "i1": (1, 1)}


@st.composite
def pointclouds(draw):
    """(message, expected (N, 3) float64 or None for InputError, whether float32 is expected)."""
    big = draw(st.booleans())
    extra = draw(st.lists(st.sampled_from(["intensity", "ring", "t"]), unique=True, max_size=3))
    names = draw(st.permutations(["x", "y", "z", *extra]))
    kinds = {n: draw(st.sampled_from(["f4", "f8"])) if n in "xyz" else draw(st.sampled_from(["f4", "u2", "i1"]))
             for n in names}
    offsets, off = {}, 0
    for n in names:
        offsets[n] = off
        off += PC2_TYPES[kinds[n]][1] + draw(st.integers(0, 3))
    step = off + draw(st.integers(0, 4))
    width, height = draw(st.integers(0, 6)), draw(st.integers(1, 3))
    row_pad = draw(st.integers(0, 8))
    row_step = width * step + row_pad
    if row_pad == 0 and draw(st.booleans()):
        row_step = 0  # left unset by the driver: rows packed
    n = width * height
    value = st.one_of(st.floats(-1e4, 1e4, allow_nan=False), st.sampled_from([math.nan, math.inf, -0.0]))
    xyz = np.array([[draw(value) for _ in range(3)] for _ in range(n)], dtype=np.float64).reshape(n, 3)
    for k, c in enumerate("xyz"):
        if kinds[c] == "f4":
            xyz[:, k] = xyz[:, k].astype(np.float32)
    # pack each value with struct at its offset: apart from the reader's numpy dtype
    order = ">" if big else "<"
    fmt = {"f4": "f", "f8": "d", "u2": "H", "i1": "b"}
    data = bytearray((row_step or width * step) * height)
    for p in range(n):
        row, col = divmod(p, width)
        base = row * (row_step or width * step) + col * step
        for c in names:
            v = xyz[p, "xyz".index(c)] if c in "xyz" else 1
            struct.pack_into(order + fmt[kinds[c]], data, base + offsets[c], v)
    fields = [SimpleNamespace(name=c, offset=offsets[c], datatype=PC2_TYPES[kinds[c]][0], count=1) for c in names]
    msg = SimpleNamespace(fields=fields, is_bigendian=big, point_step=step, width=width, height=height,
                          row_step=row_step, data=np.frombuffer(bytes(data), np.uint8))
    expected = xyz
    op = draw(st.sampled_from(["none", "none", "none", "cut", "add", "field_beyond", "short_row_step"]))
    if op == "cut" and len(data):
        msg.data = msg.data[: -draw(st.integers(1, len(data)))]
        expected = None
    elif op == "add":
        msg.data = np.r_[msg.data, np.zeros(draw(st.integers(1, 9)), np.uint8)]
        expected = None
    elif op == "field_beyond":
        c = draw(st.sampled_from("xyz"))
        next(f for f in fields if f.name == c).offset = step - PC2_TYPES[kinds[c]][1] + draw(st.integers(1, 8))
        expected = None
    elif op == "short_row_step" and width * step > 0:
        packed = row_step in (0, width * step)
        msg.row_step = width * step - draw(st.integers(1, width * step))
        if msg.row_step or not packed:  # 0 is "unset": rows packed, valid when they are
            expected = None
    if expected is not None and n and not np.isfinite(xyz).all(axis=1).any():
        expected = None  # nothing usable in the cloud
    as_f32 = not big and all(kinds[c] == "f4" for c in "xyz")
    return msg, expected, as_f32


@settings(max_examples=300)
@given(case=pointclouds())
def test_pointcloud2_read_exactly_or_rejected(case):
    from floorscan.ingest.ros_messages import pointcloud2_xyz

    msg, expected, as_f32 = case
    if expected is None:
        with pytest.raises(InputError, match=r"c.bag: PointCloud2 on '/cloud' "):
            pointcloud2_xyz(msg, "c.bag", "/cloud")
        return
    got = pointcloud2_xyz(msg, "c.bag", "/cloud")
    assert got.dtype == (np.float32 if as_f32 else np.float64)
    np.testing.assert_array_equal(got.astype(np.float64), expected)


# --- PCD headers and bodies --------------------------------------------------------------

PCD_EXTRA = {"intensity": ("F", 4), "ring": ("U", 2), "label": ("I", 4), "t": ("F", 8)}
STRUCT = {("F", 4): "f", ("F", 8): "d", ("U", 2): "H", ("I", 4): "i", ("U", 1): "B"}


@st.composite
def pcd_files(draw):
    """(bytes of a PCD file, expected (N, 3) float64 or None for InputError)."""
    extra = draw(st.lists(st.sampled_from(sorted(PCD_EXTRA)), unique=True, max_size=2))
    names = draw(st.permutations(["x", "y", "z", *extra]))
    ts = {n: ("F", draw(st.sampled_from([4, 8]))) if n in "xyz" else PCD_EXTRA[n] for n in names}
    counts = {n: 1 if n in "xyz" else draw(st.integers(1, 2)) for n in names}
    width, height = draw(st.integers(0, 5)), draw(st.integers(1, 2))
    n = width * height
    data = draw(st.sampled_from(["ascii", "binary", "binary_compressed"]))
    value = st.one_of(st.floats(-1e5, 1e5, allow_nan=False), st.sampled_from([math.nan, math.inf, -math.inf, 0.0, 1.0]))
    xyz = np.array([[draw(value) for _ in range(3)] for _ in range(n)], dtype=np.float64).reshape(n, 3)
    for k, c in enumerate("xyz"):
        if ts[c][1] == 4:
            xyz[:, k] = xyz[:, k].astype(np.float32)
    rows = []
    for p in range(n):
        row = []
        for c in names:
            row += [xyz[p, "xyz".index(c)]] if c in "xyz" else [draw(st.integers(0, 100)) for _ in range(counts[c])]
        rows.append(row)
    header = {
        "VERSION": "0.7", "FIELDS": " ".join(names), "SIZE": " ".join(str(ts[c][1]) for c in names),
        "TYPE": " ".join(ts[c][0] for c in names), "COUNT": " ".join(str(counts[c]) for c in names),
        "WIDTH": str(width), "HEIGHT": str(height), "VIEWPOINT": "0 0 0 1 0 0 0", "POINTS": str(n), "DATA": data,
    }
    if draw(st.booleans()) and all(c == 1 for c in counts.values()):
        del header["COUNT"]  # optional: 1 each
    expected = xyz
    op = draw(st.sampled_from(["none"] * 4 + ["header", "rows", "values", "bytes"]))
    if op == "header":
        key, bad = draw(st.sampled_from([
            ("POINTS", "abc"), ("POINTS", str(n + 1)), ("WIDTH", str(width + 1)), ("SIZE", "2"),
            ("SIZE", " ".join("2" if c == "x" else str(ts[c][1]) for c in names)),
            ("TYPE", " ".join("I" if c == "y" else ts[c][0] for c in names)),
            ("COUNT", " ".join("2" if c == "z" else str(counts[c]) for c in names)),
            ("FIELDS", " ".join(c for c in names if c != "z")), ("DATA", "zipped"), ("HEIGHT", "-1"),
            ("POINTS", None), ("FIELDS", " ".join(names).replace("x", "X")), ("VIEWPOINT", "0 0 0"),
        ]))
        if bad is None:
            del header[key]
        else:
            header[key] = bad
        expected = None
    comment = draw(st.sampled_from(["", "# .PCD v0.7 - Point Cloud Data file format\n"]))
    eol = "\r\n" if data == "ascii" and draw(st.booleans()) else "\n"
    head = comment + "".join(f"{k} {v}{eol}" for k, v in header.items())

    def text(v, c):
        if isinstance(v, int):
            return str(v)
        return repr(float(v)) if ts[c][1] == 8 else repr(float(np.float32(v)))

    if data == "ascii":
        lines = []
        for row in rows:
            vals, k = [], 0
            for c in names:
                for _ in range(1 if c in "xyz" else counts[c]):
                    vals.append(text(row[k], c))
                    k += 1
            lines.append(" ".join(vals))
        if op == "rows":
            if lines and draw(st.booleans()):
                del lines[draw(st.integers(0, len(lines) - 1))]
            else:
                lines.append(lines[-1] if lines else "1 2 3")
            expected = None
        elif op == "values" and lines:
            i = draw(st.integers(0, len(lines) - 1))
            vals = lines[i].split()
            how = draw(st.sampled_from(["drop", "add", "word"]))
            if how == "drop":
                del vals[draw(st.integers(0, len(vals) - 1))]
            elif how == "add":
                vals.insert(draw(st.integers(0, len(vals))), "0.5")
            else:
                vals[draw(st.integers(0, len(vals) - 1))] = draw(st.sampled_from(["abc", "1_0", "--1", "0x1p3"]))
            lines[i] = " ".join(vals)
            expected = None
        body = "".join(line + eol for line in lines).encode()
    elif data == "binary":
        chunks = []
        for row in rows:
            k = 0
            for c in names:
                for _ in range(1 if c in "xyz" else counts[c]):
                    chunks.append(struct.pack("<" + STRUCT[ts[c]], row[k]))
                    k += 1
        body = b"".join(chunks)
        if op in ("rows", "bytes", "values"):
            if body and draw(st.booleans()):
                body = body[: -draw(st.integers(1, len(body)))]
            else:
                body += b"\0" * draw(st.integers(1, 9))
            expected = None
    else:  # PCL's layout: field by field (every point's x, then every y, ...), LZF-compressed
        chunks, k0 = [], 0
        for c in names:
            width_c = 1 if c in "xyz" else counts[c]
            for row in rows:
                for j in range(width_c):
                    chunks.append(struct.pack("<" + STRUCT[ts[c]], row[k0 + j]))
            k0 += width_c
        plain = b"".join(chunks)
        packed = lzf_compress(plain)
        sizes = [len(packed), len(plain)]
        if op in ("rows", "values"):
            j, delta = draw(st.integers(0, 1)), draw(st.sampled_from([-1, 1, 12]))
            sizes[j] += delta if sizes[j] + delta >= 0 else 1  # a stated size wrong
            expected = None
        body = struct.pack("<II", *sizes) + packed
        if len({ts[c] for c in "xyz"}) > 1:
            expected = None  # x, y, z of different sizes: not read (Open3D decompresses)
        if op == "bytes":
            if body and draw(st.booleans()):
                body = body[: -draw(st.integers(1, len(body)))]
            else:
                body += b"\0" * draw(st.integers(1, 9))
            expected = None
    return head.encode() + body, expected


@settings(max_examples=300)
@given(case=pcd_files())
def test_pcd_read_exactly_or_rejected(workdir, case):
    from floorscan.ingest.pcd_file import read_pcd_xyz

    raw, expected = case
    path = workdir / "p.pcd"
    path.write_bytes(raw)
    if expected is None:
        with pytest.raises(InputError, match=r"p.pcd"):
            read_pcd_xyz(path)
        return
    got = read_pcd_xyz(path)
    assert got.dtype == np.float64
    np.testing.assert_array_equal(got, expected)


def lzf_compress(data: bytes) -> bytes:
    """A plain LZF encoder, for the test: at each byte the longest match of 3 to 264 bytes
    at a distance up to 300 (overlapping ones included) becomes a back reference, the
    rest literal runs of up to 32 bytes (liblzf's block format)."""
    out, lit, i = bytearray(), bytearray(), 0

    def flush():
        while lit:
            run = lit[:32]
            out.append(len(run) - 1)
            out.extend(run)
            del lit[:32]

    while i < len(data):
        best, dist = 0, 0
        for d in range(1, min(i, 300) + 1):
            n = 0
            while i + n < len(data) and n < 264 and data[i + n] == data[i + n - d]:
                n += 1
            if n > best:
                best, dist = n, d
        if best >= 3:
            flush()
            n, d = best - 2, dist - 1
            if n < 7:
                out += bytes([(n << 5) | (d >> 8), d & 0xFF])
            else:
                out += bytes([(7 << 5) | (d >> 8), n - 7, d & 0xFF])
            i += best
        else:
            lit.append(data[i])
            i += 1
    flush()
    return bytes(out)

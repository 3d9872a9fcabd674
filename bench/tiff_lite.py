"""Minimal greyscale TIFF reader/writer (Python standard library only) for bench/dic_challenge.py.

Reads baseline TIFF: one sample per pixel, 8 or 16 bits, strips, compression none (1), LZW (5,
with or without horizontal predictor 2) or PackBits (32773), either byte order. That covers the
DIC Challenge 1.0 images and what OpenCV writes. Anything else raises TiffError naming the file
and the tag. Writes uncompressed little-endian greyscale TIFFs (used to crop images of unequal
size to their common size).

    img = read_tiff("Sample14 Reference.tif")   # Image(width, height, bits, pixels: list[int])
    write_tiff("crop.tif", crop(img, 2048, 589))
"""

import struct
from dataclasses import dataclass


class TiffError(Exception):
    pass


@dataclass
class Image:
    width: int
    height: int
    bits: int
    pixels: list  # row-major, width * height ints

    def at(self, x, y):
        return self.pixels[y * self.width + x]


_TYPE_SIZES = {1: 1, 3: 2, 4: 4, 16: 8}  # BYTE, SHORT, LONG, LONG8 (unused in classic TIFF)


def _read_ifd(data, path):
    if data[:2] == b"II":
        end = "<"
    elif data[:2] == b"MM":
        end = ">"
    else:
        raise TiffError(f"{path}: not a TIFF file (byte-order mark {data[:2]!r})")
    magic, offset = struct.unpack(end + "HI", data[2:8])
    if magic != 42:
        raise TiffError(f"{path}: unsupported TIFF magic {magic} (BigTIFF is not read)")
    (count,) = struct.unpack(end + "H", data[offset:offset + 2])
    tags = {}
    for i in range(count):
        entry = data[offset + 2 + 12 * i: offset + 14 + 12 * i]
        tag, typ, n = struct.unpack(end + "HHI", entry[:8])
        size = _TYPE_SIZES.get(typ)
        if size is None:
            continue  # RATIONAL, ASCII, ...: not needed here
        fmt = {1: "B", 3: "H", 4: "I"}[typ]
        raw = entry[8:12] if size * n <= 4 else data[struct.unpack(end + "I", entry[8:12])[0]:][:size * n]
        tags[tag] = list(struct.unpack(end + fmt * n, raw[:size * n]))
    return end, tags


def read_size(path):
    """(width, height) from the header alone."""
    with open(path, "rb") as f:
        data = f.read()
    _, tags = _read_ifd(data, path)
    return tags[256][0], tags[257][0]


def _lzw_decode(src):
    out = bytearray()
    table = [bytes([i]) for i in range(256)] + [b"", b""]
    code_len, bitpos, prev = 9, 0, None
    nbits = len(src) * 8
    while bitpos + code_len <= nbits:
        byte = bitpos >> 3
        chunk = int.from_bytes(src[byte:byte + 4].ljust(4, b"\0"), "big")
        code = (chunk >> (32 - (bitpos & 7) - code_len)) & ((1 << code_len) - 1)
        bitpos += code_len
        if code == 256:  # clear
            table = table[:258]
            code_len, prev = 9, None
            continue
        if code == 257:  # end of information
            break
        if prev is None:
            entry = table[code]
        elif code < len(table):
            entry = table[code]
            table.append(prev + entry[:1])
        else:
            entry = prev + prev[:1]
            table.append(entry)
        out += entry
        prev = entry
        if len(table) + 1 >= (1 << code_len) and code_len < 12:  # early change
            code_len += 1
    return bytes(out)


def _packbits_decode(src):
    out, i = bytearray(), 0
    while i < len(src):
        n = src[i]
        i += 1
        if n < 128:
            out += src[i:i + n + 1]
            i += n + 1
        elif n > 128:
            out += src[i:i + 1] * (257 - n)
            i += 1
    return bytes(out)


def read_tiff(path):
    with open(path, "rb") as f:
        data = f.read()
    end, tags = _read_ifd(data, path)
    width, height = tags[256][0], tags[257][0]
    bits = tags.get(258, [1])[0]
    samples = tags.get(277, [1])[0]
    compression = tags.get(259, [1])[0]
    predictor = tags.get(317, [1])[0]
    photometric = tags.get(262, [1])[0]
    if samples != 1 or bits not in (8, 16) or photometric not in (0, 1):
        raise TiffError(f"{path}: only greyscale 8/16-bit TIFFs are read (SamplesPerPixel "
                        f"{samples}, BitsPerSample {bits}, PhotometricInterpretation {photometric})")
    if 322 in tags:
        raise TiffError(f"{path}: tiled TIFFs are not read (TileWidth present)")
    decoders = {1: lambda s: s, 5: _lzw_decode, 32773: _packbits_decode}
    if compression not in decoders:
        raise TiffError(f"{path}: Compression {compression} is not read (1, 5 LZW, 32773 PackBits are)")
    rows_per_strip = tags.get(278, [height])[0]
    raw = bytearray()
    for off, n in zip(tags[273], tags[279]):
        strip = decoders[compression](data[off:off + n])
        bytes_per_row = width * bits // 8
        rows = min(rows_per_strip, height - len(raw) // bytes_per_row)
        strip = bytearray(strip[:rows * bytes_per_row])
        if predictor == 2:
            _undo_predictor(strip, width, rows, bits, end)
        raw += strip
    expected = width * height * bits // 8
    if len(raw) < expected:
        raise TiffError(f"{path}: pixel data truncated ({len(raw)} of {expected} bytes)")
    if bits == 8:
        pixels = list(raw[:expected])
    else:
        pixels = list(struct.unpack(f"{end}{width * height}H", bytes(raw[:expected])))
    if photometric == 0:  # WhiteIsZero
        top = (1 << bits) - 1
        pixels = [top - p for p in pixels]
    return Image(width, height, bits, pixels)


def _undo_predictor(strip, width, rows, bits, end):
    if bits == 8:
        for r in range(rows):
            base = r * width
            for i in range(base + 1, base + width):
                strip[i] = (strip[i] + strip[i - 1]) & 0xFF
    else:
        fmt = end + "H"
        for r in range(rows):
            base = r * width * 2
            prev = struct.unpack_from(fmt, strip, base)[0]
            for i in range(1, width):
                cur = (struct.unpack_from(fmt, strip, base + 2 * i)[0] + prev) & 0xFFFF
                struct.pack_into(fmt, strip, base + 2 * i, cur)
                prev = cur


def crop(img, width, height):
    """Top-left width x height part of `img`."""
    if width > img.width or height > img.height:
        raise TiffError(f"cannot crop {img.width}x{img.height} to {width}x{height}")
    rows = [img.pixels[y * img.width: y * img.width + width] for y in range(height)]
    return Image(width, height, img.bits, [p for row in rows for p in row])


def write_tiff(path, img):
    """Uncompressed little-endian greyscale TIFF, one strip."""
    nbytes = img.width * img.height * img.bits // 8
    entries = [(256, 4, img.width), (257, 4, img.height), (258, 3, img.bits), (259, 3, 1),
               (262, 3, 1), (273, 4, 0), (277, 3, 1), (278, 4, img.height), (279, 4, nbytes)]
    ifd_offset = 8
    data_offset = ifd_offset + 2 + 12 * len(entries) + 4
    out = bytearray(b"II" + struct.pack("<HI", 42, ifd_offset))
    out += struct.pack("<H", len(entries))
    for tag, typ, value in entries:
        if tag == 273:
            value = data_offset
        if typ == 3:
            out += struct.pack("<HHIHH", tag, typ, 1, value, 0)
        else:
            out += struct.pack("<HHII", tag, typ, 1, value)
    out += struct.pack("<I", 0)
    if img.bits == 8:
        out += bytes(img.pixels)
    else:
        out += struct.pack(f"<{len(img.pixels)}H", *img.pixels)
    with open(path, "wb") as f:
        f.write(out)

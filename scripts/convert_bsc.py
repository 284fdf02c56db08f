#!/usr/bin/env python3
"""Converts the Bright Star Catalogue as Debian's xplanet package ships it
(usr/share/xplanet/stars/BSC: declination in degrees, right ascension in hours, visual
magnitude, then names) into assets/bsc5.bin, the compact file skytune embeds.

The catalogue (Yale Bright Star Catalogue, 5th revised edition, Hoffleit and Warren 1991) is in
the public domain. Run once:

    apt-get download xplanet && dpkg-deb -x xplanet_*.deb xplanet
    python3 scripts/convert_bsc.py xplanet/usr/share/xplanet/stars/BSC assets/bsc5.bin

Format (little-endian): b"SKYBSC1\\0", u32 star count, then per star i16 declination (0.01
degree), u16 right ascension (24 h / 65536), i16 visual magnitude (0.01), brightest first.
Read by src/sky/starfield.rs.
"""
import struct
import sys


def main(source, target):
    stars = []
    with open(source, encoding="latin-1") as f:
        for line in f:
            fields = line.split()
            if not fields or line.lstrip().startswith("#") or len(fields) < 3:
                continue
            dec, ra, mag = float(fields[0]), float(fields[1]), float(fields[2])
            stars.append((mag, dec, ra))
    stars.sort()
    out = bytearray(b"SKYBSC1\0")
    out += struct.pack("<I", len(stars))
    for mag, dec, ra in stars:
        out += struct.pack("<hHh", round(dec * 100), round(ra / 24 * 65536) % 65536, round(mag * 100))
    with open(target, "wb") as f:
        f.write(out)
    print(f"{target}: {len(stars)} stars, {len(out)} bytes")


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])

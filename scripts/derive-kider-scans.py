#!/usr/bin/env python3
"""Derive the small scan files of data/measured/kider2014/ from the Kider et al. 2014 sky
measurements (https://github.com/spectralskylight/sky-measurements-2014, Apache-2.0).

Usage: derive-kider-scans.py CLONE_OF_THE_REPOSITORY OUT_DIR   (needs `pip install py7zr`)

Each scan's 81 spectral radiance files (ASD spectroradiometer, W m^-2 sr^-1 nm^-1, 350-2500 nm)
become one CSV row per direction: the mean radiance over 10 nm around 680, 550 and 440 nm (the
models' channels). The archive's azimuths run counter-clockwise from north (the brightest
samples of every scan lie at 360 degrees minus the sun's compass azimuth); the rows give compass
azimuths, clockwise from north.
"""
import os, re, sys, glob, tempfile
import py7zr

LAT, LON, UTC_OFFSET_H = 42.443449, -76.481962, -4  # Rhodes Hall, Cornell; EDT on both days
BANDS = {"r": 680, "g": 550, "b": 440}
# Sample 0 (due north, 12 degrees up) reads 0.4 to 0.75 of its two neighbours in 18 of the 20
# scans (the others: 0.96 to 1.05): something in the scanner's way or its first reading. It is
# kept, flagged `use = 0`.
OBSTRUCTED = {0}
# Held out of any tuning: the second day, low sun included.
HELD_OUT_DAY = "2013-09-24"

def main(repo, out):
    os.makedirs(out, exist_ok=True)
    for archive in sorted(glob.glob(os.path.join(repo, "data", "*", "RADIANCE", "*.7z"))):
        m = re.search(r"(\d{4}-\d\d-\d\d)___(\d\d)\.(\d\d)\.(\d\d)\.7z$", archive)
        day, hh, mm, ss = m.groups()
        rows = {}
        with tempfile.TemporaryDirectory() as tmp:
            with py7zr.SevenZipFile(archive) as z:
                z.extractall(tmp)
            for name in glob.glob(os.path.join(tmp, "**", "*.asd.rad.txt"), recursive=True):
                s = re.search(r"_-_(\d+)____([\d.]+)___([\d.]+)\.asd\.rad\.txt$", name)
                index, az_archive, elev = int(s.group(1)), float(s.group(2)), float(s.group(3))
                spectrum = {}
                with open(name, encoding="latin-1") as f:
                    for line in f:
                        p = line.split()
                        if len(p) == 2 and p[0].isdigit():
                            spectrum[int(p[0])] = float(p[1])
                means = [sum(spectrum[w] for w in range(c - 5, c + 6)) / 11 for c in BANDS.values()]
                rows[index] = ((360.0 - az_archive) % 360.0, elev, means)
        split = "held_out" if day == HELD_OUT_DAY else "tuning"
        path = os.path.join(out, f"{day}_{hh}-{mm}.csv")
        with open(path, "w") as f:
            f.write("# Kider et al. 2014, \"A Framework for the Experimental Comparison of Solar and Skydome Illumination\"\n")
            f.write("# source: https://github.com/spectralskylight/sky-measurements-2014 (Apache-2.0), " + os.path.basename(archive) + "\n")
            f.write("# derived by scripts/derive-kider-scans.py: mean radiance over 10 nm around 680, 550, 440 nm, W m^-2 sr^-1 nm^-1; compass azimuths\n")
            f.write(f"# latitude_deg = {LAT}\n# longitude_deg = {LON}\n# local_time = {day}T{hh}:{mm}:{ss}\n# utc_offset_h = {UTC_OFFSET_H}\n# split = {split}\n")
            f.write("# use = 0: left out of comparisons (see scripts/derive-kider-scans.py)\n")
            f.write("sample,azimuth_deg,elevation_deg,r,g,b,use\n")
            for index in sorted(rows):
                az, elev, (r, g, b) = rows[index]
                f.write(f"{index},{az:g},{elev:g},{r:.6e},{g:.6e},{b:.6e},{0 if index in OBSTRUCTED else 1}\n")
        print(path, len(rows))

if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])

#!/usr/bin/env python3
"""Count the green and red pixels of a render of Khronos' TextureSettingsTest asset, split into its "Test" and
"Sample pass" columns (the widest gap between green columns of pixels separates them).

Usage: checker_columns.py IMAGE.ppm   (binary PPM, e.g. `oiiotool render.png -o render.ppm`)
Prints "red R test T sample S": R red pixels (the asset's failure marks are red), T and S green pixels left and
right of the gap. tests/report_cli.sh asserts on these counts.
"""
import sys


def read_ppm(path):
    data = open(path, "rb").read()
    fields, pos = [], 0
    while len(fields) < 4:  # magic, width, height, maxval, each followed by whitespace (comments skipped)
        while data[pos:pos + 1].isspace():
            pos += 1
        if data[pos:pos + 1] == b"#":
            pos = data.index(b"\n", pos) + 1
            continue
        end = pos
        while not data[end:end + 1].isspace():
            end += 1
        fields.append(data[pos:end])
        pos = end
    if fields[0] != b"P6" or int(fields[3]) != 255:
        sys.exit(f"{path}: not an 8-bit binary PPM")
    width, height = int(fields[1]), int(fields[2])
    return width, height, data[pos + 1:pos + 1 + 3 * width * height]


def main():
    width, height, pixels = read_ppm(sys.argv[1])
    red, green_columns = 0, [0] * width
    for i in range(width * height):
        r, g, b = pixels[3 * i], pixels[3 * i + 1], pixels[3 * i + 2]
        if r > 80 and r > 2 * g and r > 2 * b:
            red += 1
        if g > 80 and g > 2 * r and g > 2 * b:
            green_columns[i % width] += 1
    used = [x for x in range(width) if green_columns[x] > 0]
    if not used:
        print(f"red {red} test 0 sample 0")
        return
    best_run, split, run = 0, used[0], 0
    for x in range(used[0], used[-1] + 1):
        run = run + 1 if green_columns[x] == 0 else 0
        if run > best_run:
            best_run, split = run, x
    print(f"red {red} test {sum(green_columns[:split])} sample {sum(green_columns[split:])}")


main()

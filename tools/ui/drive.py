#!/usr/bin/env python3
"""Drives Ductile Studio as a user would, under Xvfb with xdotool, and checks what it sees.

Usage: drive.py STUDIO_BINARY OUT_DIR

Needs `Xvfb`, `xdotool` and `xwd` (apt: xvfb xdotool x11-apps) and software Vulkan
(mesa-vulkan-drivers). Opens the Studio on the built-in identikit head in a 1280x800 window
and, with real (XTEST) mouse and keyboard input:

1. drags the first identikit slider ("Brows higher / lower") to the right: the head in the
   3-D view must change while the button is held;
2. releases it, presses Ctrl+Z once and Escape (to hide the gizmo of the macro the drag
   selected): the 3-D view must be back to the start, pixel for pixel (one drag = one undo
   step);
3. presses Ctrl+Shift+Z: the head must be deformed again;
4. drags on empty viewport space (orbit) and scrolls (zoom): the view must change.

Screenshots of every stage are written to OUT_DIR as PNG. Exits 1 with a message naming the
failed stage. The slider position is that of the default 1280x800 layout.
"""
import os
import struct
import subprocess
import sys
import time
import zlib

WIDTH, HEIGHT = 1280, 800
# The 3-D view of the default layout (between the side panels, under the menu bar).
VIEW = (365, 40, 835, 705)
SLIDER = (916, 227)  # The handle of the first identikit slider at value 0.


def xwd_rgb(display):
    """The root window as (width, height, RGB bytes), from `xwd` (32-bit ZPixmap)."""
    data = subprocess.run(["xwd", "-root", "-silent", "-display", display],
                          check=True, capture_output=True).stdout
    f = struct.unpack(">25I", data[:100])
    header_size, bits_per_pixel, bytes_per_line = f[0], f[11], f[12]
    width, height, ncolors, byte_order = f[4], f[5], f[19], f[7]
    if bits_per_pixel != 32:
        sys.exit(f"xwd: {bits_per_pixel} bits per pixel, expected 32")
    pixels = data[header_size + 12 * ncolors:]
    rgb = bytearray(width * height * 3)
    for y in range(height):
        row = pixels[y * bytes_per_line:y * bytes_per_line + width * 4]
        out = rgb[y * width * 3:(y + 1) * width * 3]
        if byte_order == 0:  # LSBFirst: B G R X
            out[0::3], out[1::3], out[2::3] = row[2::4], row[1::4], row[0::4]
        else:  # MSBFirst: X R G B
            out[0::3], out[1::3], out[2::3] = row[1::4], row[2::4], row[3::4]
        rgb[y * width * 3:(y + 1) * width * 3] = out
    return width, height, bytes(rgb)


def write_png(path, width, height, rgb):
    raw = b"".join(b"\x00" + rgb[y * width * 3:(y + 1) * width * 3] for y in range(height))

    def chunk(kind, body):
        return (struct.pack(">I", len(body)) + kind + body
                + struct.pack(">I", zlib.crc32(kind + body) & 0xFFFFFFFF))

    with open(path, "wb") as out:
        out.write(b"\x89PNG\r\n\x1a\n"
                  + chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0))
                  + chunk(b"IDAT", zlib.compress(raw, 6)) + chunk(b"IEND", b""))


def view_crop(shot):
    width, _, rgb = shot
    x0, y0, x1, y1 = VIEW
    return b"".join(rgb[(y * width + x0) * 3:(y * width + x1) * 3] for y in range(y0, y1))


def changed_pixels(a, b):
    ca, cb = view_crop(a), view_crop(b)
    return sum(1 for i in range(0, len(ca), 3) if ca[i:i + 3] != cb[i:i + 3])


def main():
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    studio, out_dir = sys.argv[1], sys.argv[2]
    os.makedirs(out_dir, exist_ok=True)
    display = ":%d" % (90 + os.getpid() % 100)
    xvfb = subprocess.Popen(["Xvfb", display, "-screen", "0", f"{WIDTH}x{HEIGHT}x24"],
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    # The Studio is killed at the end with unsaved edits: its recovery file goes to a folder
    # of this run, not to the user's.
    recovery = os.path.join(os.path.abspath(out_dir), "recovery")
    env = dict(os.environ, DISPLAY=display, DUCTILE_RECOVERY_DIR=recovery)
    app = None
    try:
        time.sleep(2)
        log = open(os.path.join(out_dir, "studio.log"), "w")
        app = subprocess.Popen([studio, "--size", f"{WIDTH}x{HEIGHT}"], env=env,
                               stdout=log, stderr=subprocess.STDOUT)

        def xdo(*args):
            subprocess.run(["xdotool", *map(str, args)], env=env, check=True)

        def shot(name, settle=2.0):
            time.sleep(settle)
            s = xwd_rgb(display)
            write_png(os.path.join(out_dir, name + ".png"), *s)
            return s

        # Wait for the window, focus it (there is no window manager) and let it settle.
        for _ in range(120):
            found = subprocess.run(["xdotool", "search", "--name", "Ductile Studio"],
                                   env=env, capture_output=True, text=True).stdout.split()
            if found:
                break
            if app.poll() is not None:
                sys.exit(f"the Studio exited with status {app.returncode} (see studio.log)")
            time.sleep(0.5)
        else:
            sys.exit("no Studio window after 60 s")
        xdo("windowfocus", "--sync", found[0])
        start = shot("1-start", settle=20.0)

        xdo("mousemove", *SLIDER)
        time.sleep(0.5)
        xdo("mousedown", 1)
        for x in range(SLIDER[0] + 5, SLIDER[0] + 50, 8):
            xdo("mousemove", x, SLIDER[1])
            time.sleep(0.3)
        during = shot("2-dragging")
        if changed_pixels(start, during) < 200:
            sys.exit("stage 1: the head did not change while the slider was dragged")
        xdo("mouseup", 1)
        shot("3-released")

        xdo("key", "ctrl+z")
        time.sleep(1.0)
        xdo("key", "Escape")  # The drag selected the macro; its gizmo is not part of the head.
        undone = shot("4-undone")
        if (n := changed_pixels(start, undone)) != 0:
            sys.exit(f"stage 2: after one Ctrl+Z the 3-D view differs from the start "
                     f"in {n} pixels")

        xdo("key", "ctrl+shift+z")
        redone = shot("5-redone")
        if changed_pixels(start, redone) < 200:
            sys.exit("stage 3: after Ctrl+Shift+Z the head is not deformed again")

        xdo("mousemove", 600, 650)
        xdo("mousedown", 1)
        for x in range(610, 720, 15):
            xdo("mousemove", x, 640)
            time.sleep(0.3)
        xdo("mouseup", 1)
        for _ in range(3):
            xdo("click", 4)
            time.sleep(0.3)
        moved = shot("6-orbit-zoom")
        if changed_pixels(redone, moved) < 1000:
            sys.exit("stage 4: orbit and zoom did not change the view")
        print(f"ok: slider drag, one-step undo, redo, orbit and zoom ({out_dir})")
    finally:
        if app is not None:
            app.kill()
        xvfb.kill()


if __name__ == "__main__":
    main()

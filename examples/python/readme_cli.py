#!/usr/bin/env python3
"""The README's command-line examples, in Python (docs/python.md).

Usage: PYTHONPATH=build/release/python python3 examples/python/readme_cli.py [OUT_DIR]
       [--frames N]   (frames of the orbit movie; the README's is 120)

Each step names the CLI command it reproduces; the outputs go to OUT_DIR
(default out/python). Run from the repository root (../shared/data).
"""
import argparse
import os

import volvis

HEAD = "../shared/data/volumes/ct_head.nrrd"


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("out", nargs="?", default="out/python")
    ap.add_argument("--frames", type=int, default=120)
    ap.add_argument("--size", type=int, default=512)
    args = ap.parse_args()
    os.makedirs(args.out, exist_ok=True)

    def out(name):
        return os.path.join(args.out, name)

    size = (args.size, args.size)
    # volvis info ct_head.nrrd
    head = volvis.open(HEAD)
    print(head)
    # volvis render ct_head.nrrd -o head.png --tf 100:1500 --azimuth 30
    world = volvis.World.for_volume(head, tf_range=(100, 1500), azimuth=30, size=size)
    volvis.save_png(volvis.render(world), out("head.png"))
    # volvis render ct_head.nrrd -o mip.png --mode mip
    volvis.save_png(volvis.render(head, mode="mip", size=size), out("mip.png"))
    # volvis render ct_head.nrrd -o bone.png --mode iso --iso 300
    bone = volvis.World.for_volume(head, mode="iso", isovalue=300, size=size)
    volvis.save_png(volvis.render(bone), out("bone.png"))
    # volvis render examples/ct_head.json -o scene.png
    scene = volvis.load_scene("examples/ct_head.json")
    volvis.save_png(volvis.render(scene), out("scene.png"))
    # volvis convert nut.slc nut.nrrd
    volvis.open("../shared/data/volumes/nut.slc").save(out("nut.nrrd"))
    # volvis compress ct_head.nrrd head.vvc --rate 1 --check
    vvc = volvis.compress(head, rate=1)
    vvc.save(out("head.vvc"))
    print(vvc)
    # volvis render ct_head.nrrd --renderer fourier --set vvc=head.vvc --ortho --mode xray --tf -1024:300
    xray = volvis.World.for_volume(head, mode="xray", tf_range=(-1024, 300), size=size)
    xray.view.projection = "orthographic"
    xray.view.frame(*xray.bounds())
    volvis.save_png(volvis.render(xray, renderer="fourier", vvc=out("head.vvc")),
                             out("fourier.png"))
    # volvis isosurface ct_head.nrrd --iso 300 -o bone.ply
    mesh = volvis.isosurface(head, 300)
    mesh.save(out("bone.ply"))
    print(mesh)
    # volvis measure ct_head.nrrd --iso 300
    m = volvis.measure(head, isovalue=300)
    print("area %.1f %s^2, volume %.1f %s^3" % (m.area, m.unit, m.volume, m.unit))
    # volvis filter ct_head.nrrd smooth.nrrd --gaussian 1.5 --median 1
    volvis.filter(head, gaussian=1.5, median=1).save(out("smooth.nrrd"))
    # volvis filter ct_head.nrrd labels.nrrd --threshold 300: --components 26
    labels = volvis.filter(head, threshold="300:", components=26)
    labelled = volvis.World.for_volume(labels, size=size)
    labelled.objects[0].segmentation = "labels"
    volvis.save_png(volvis.render(labelled), out("labels.png"))
    # volvis voxelize examples/nut_bolt.json -o nut_bolt.nrrd --size 256
    volvis.voxelize("examples/nut_bolt.json", size=128).save(out("nut_bolt.nrrd"))
    # volvis animate ct_head.nrrd --tf 100:1500 --orbit 360 --frames 120 -o head.mp4
    movie = volvis.World.for_volume(head, tf_range=(100, 1500), size=size)
    stats = volvis.orbit(360, frames=args.frames).render(out("head.mp4"), movie)
    print("movie: %d frames in %.1f s" % (stats["frames"], stats["total_s"]))


if __name__ == "__main__":
    main()

/*
 * volvis-gui: the VolVis desktop application (GTK 4). A thin client of
 * libvolvis: everything it does goes through the public API, so the library
 * and the CLI can reproduce whatever it shows. See docs/gui.md.
 */
#include <stdio.h>
#include <string.h>

#include <volvis/volvis.h>

#include "vvg-application.h"
#include "vvg-document.h"
#include "vvg-scene-view.h"

static void
usage(FILE *out) {
    fprintf(out,
            "usage: volvis-gui [FILE...]\n"
            "       volvis-gui --help | --version\n"
            "\n"
            "VolVis %s: the desktop application. Opens volumes (NRRD, NIfTI, MetaImage,\n"
            "VTK, SLC, ...), meshes (OBJ, PLY, STL, OFF, ...) and scene files (.json).\n"
            "Volumes whose level 0 holds more than a quarter of VOLVIS_MEMORY_LIMIT, and\n"
            ".vvb files, are drawn out of core: multiresolution files (OME-Zarr,\n"
            "BigDataViewer, Imaris, .vvb with levels) by level of detail, sharpening as\n"
            "chunks arrive, bricked files brick by brick; all files share the one memory\n"
            "limit (the View page's cache line).\n"
            "\n"
            "The 3-D view fills the window; \"4 views\" adds axial, coronal and sagittal\n"
            "slice views (click: move the cursor; right drag: window/level; wheel: next\n"
            "slice). Pages: Objects, Transfer function (editor, presets), View, Lights,\n"
            "Cut planes, Rendering, Measurement, Modeling, Filtering, Animator, Input\n"
            "devices (3-D mouse and game controllers present at start are used).\n"
            "Drag in the view: rotate (Shift: pan, Ctrl: zoom, Alt: the selected object;\n"
            "right button: pan); wheel: zoom.\n"
            "Keys: Ctrl+O open, Ctrl+I import raw, Ctrl+D browse DICOM, Ctrl+S save\n"
            "session, Ctrl+Z undo, Ctrl+Shift+Z redo, Ctrl+R render, Ctrl+0 frame all,\n"
            "Ctrl+1 / Ctrl+4 one or four views, Ctrl+W close, Ctrl+Q quit.\n"
            "\n"
            "Environment (docs/gui.md):\n"
            "  VOLVIS_FRAME_LOG=FILE     append a line per frame shown\n"
            "  VOLVIS_FRAME_DIR=DIR      write each full-quality frame to DIR/full.png\n"
            "  VOLVIS_MEMORY_LIMIT=SIZE  memory for the bricks and chunks of all files out\n"
            "                            of core together (bytes, or with K, M or G;\n"
            "                            default 1G)\n"
            "  VOLVIS_INPUT_SOCKET=PATH  listen for input devices on a Unix socket at start\n"
            "                            (protocol: docs/input.md)\n"
            "  VOLVIS_INPUT_REPLAY=FILE  replay a recording of input devices at start\n"
            "  VOLVIS_DEVICE_DIR=DIR     more device information-base files\n"
            "  VOLVIS_NO_AUTO_DEVICES=1  do not open the devices present at start\n"
            "  VOLVIS_SLICE_LOG=FILE     append a line each time a slice view resamples\n"
            "  GSK_RENDERER=NAME         GTK's renderer (gl, cairo, vulkan); unset, a\n"
            "                            software OpenGL (llvmpipe) gets cairo\n",
            vv_version());
}

int
main(int argc, char **argv) {
    vvg_scene_view_set_start_time(g_get_monotonic_time());
    /* The renderers' OpenMP threads share the cores with the UI thread and
     * the display server: threads that spin while they wait for work take
     * the time the UI needs to show frames. Unless the user says otherwise,
     * they sleep instead. */
    g_setenv("OMP_WAIT_POLICY", "PASSIVE", FALSE);
    for (int i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "--help") || !strcmp(argv[i], "-h")) {
            usage(stdout);
            return 0;
        }
        if (!strcmp(argv[i], "--version") || !strcmp(argv[i], "-V")) {
            printf("volvis-gui %s\n", vv_version());
            return 0;
        }
        if (argv[i][0] == '-' && argv[i][1] != '\0' && strcmp(argv[i], "--")) {
            fprintf(stderr, "volvis-gui: unknown option '%s' (see --help)\n", argv[i]);
            return 2;
        }
    }
    /* one budget for the bricks and chunks of every file out of core, set
     * before any file opens (vv_open's VV_OPEN_AUTO reads it) */
    vv_cache_set_limit(vv_cache_process(), vvg_document_memory_limit());
    VvgApplication *app = vvg_application_new();
    int status = g_application_run(G_APPLICATION(app), argc, argv);
    g_object_unref(app);
    return status;
}

/*
 * volvis: the command-line tool. Dispatches a table of subcommands, one file
 * each (cmd_info.c, cmd_render.c, cmd_renderers.c, cmd_convert.c, cmd_compress.c,
 * cmd_isosurface.c, cmd_measure.c, cmd_voxelize.c, cmd_filter.c, cmd_devices.c, cmd_animate.c,
 * cmd_slice.c; serve/ for `volvis serve`). See
 * docs/cli.md.
 */
#include <signal.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"

static const cli_command commands[] = {
    {"info", "print a volume's header, value range and histogram", cli_info_main, cli_info_usage},
    {"render", "render a volume or a scene file to a PNG image", cli_render_main, cli_render_usage},
    {"slice", "one axial, coronal, sagittal or oblique slice of a volume to a PNG; probe a value",
     cli_slice_main, cli_slice_usage},
    {"serve", "serve the browser view: 3-D view, slices, presets, rendered here (prints a URL)",
     cli_serve_main, cli_serve_usage},
    {"renderers", "list the renderers, what they draw and their options (--json)",
     cli_renderers_main, cli_renderers_usage},
    {"animate", "render an animation (orbit, keyframes, flight path) to PNGs, MP4 or WebM",
     cli_animate_main, cli_animate_usage},
    {"filter", "smooth, resample, differentiate or segment a volume (filters in order)",
     cli_filter_main, cli_filter_usage},
    {"convert", "convert any readable volume to any format that writes", cli_convert_main,
     cli_convert_usage},
    {"voxelize", "volume-sample a geometric model (scene or mesh) to NRRD or SLC",
     cli_voxelize_main, cli_voxelize_usage},
    {"compress", "compress a volume to a .vvc file (Fourier-domain, JPEG-like)", cli_compress_main,
     cli_compress_usage},
    {"decompress", "decompress a .vvc file to NRRD or SLC", cli_decompress_main,
     cli_decompress_usage},
    {"isosurface", "extract an isosurface (or a preview of it) to PLY, OBJ, STL, glTF or VTP",
     cli_isosurface_main, cli_isosurface_usage},
    {"measure", "isosurface area and volume, histograms, distances; mesh area and volume",
     cli_measure_main, cli_measure_usage},
    {"devices", "list input devices, their information base and assignments; replay, record",
     cli_devices_main, cli_devices_usage},
};
#define N_COMMANDS ((int)(sizeof commands / sizeof commands[0]))

static const cli_command *
find_command(const char *name) {
    for (int i = 0; i < N_COMMANDS; i++)
        if (strcmp(commands[i].name, name) == 0)
            return &commands[i];
    return NULL;
}

static void
usage(FILE *out) {
    fprintf(out,
            "usage: volvis COMMAND [OPTIONS] ARGS...\n"
            "       volvis COMMAND --help\n"
            "       volvis --help | --version\n"
            "\n"
            "VolVis %s: a volume visualization system.\n"
            "\n"
            "Commands:\n",
            vv_version());
    for (int i = 0; i < N_COMMANDS; i++)
        fprintf(out, "  %-10s %s\n", commands[i].name, commands[i].summary);
    fprintf(out, "  %-10s %s\n", "help", "show this help, or 'help COMMAND' for a command's");
    fprintf(out, "\n"
                 "Global option (any command, anywhere on the line):\n"
                 "  --max-memory SIZE  memory budget of one volume, grid or mesh read or\n"
                 "                     decoded (e.g. 512M, 8G; default: half of the available\n"
                 "                     memory, the memory cgroup's limit counted, or\n"
                 "                     $VOLVIS_MAX_MEMORY). A file whose header asks for more\n"
                 "                     is refused before anything is allocated; so is one\n"
                 "                     past the cgroup's limit, whatever the budget.\n"
                 "\n"
                 "NRRD, NIfTI, TIFF and DICOM files, meshes, .vtu and NetCDF grids are read\n"
                 "by their libraries in a separate, locked-down process (volvis-reader); a\n"
                 "crash there is one line of error.\n"
                 "VOLVIS_SANDBOX=0 reads them in this process; VOLVIS_SANDBOX=all reads\n"
                 "our own formats (SLC, MetaImage, VTK, OpenDX, PLOT3D, raw, .vvb) there too\n"
                 "(docs/security.md). A volume's voxels are copied out of the reader where\n"
                 "the kernel allows (process_vm_readv), else passed in a sealed memfd;\n"
                 "VOLVIS_SANDBOX_PEEK=0 always takes the memfd.\n"
                 "\n"
                 "An OME-Zarr, N5 or precomputed store may be a URL wherever a file is taken:\n"
                 "http://, https://, s3://BUCKET/KEY or gs://BUCKET/PATH (a public bucket,\n"
                 "anonymously; STORAGE_EMULATOR_HOST sends it elsewhere), also behind\n"
                 "Neuroglancer's precomputed://, n5:// or zarr:// (fetched by byte range in\n"
                 "this process, TLS verified). The environment sets the transport:\n"
                 "VOLVIS_HTTP_MAX_IN_FLIGHT (32), VOLVIS_HTTP_RETRIES (3),\n"
                 "VOLVIS_HTTP_CONNECT_TIMEOUT (10 s),\n"
                 "VOLVIS_HTTP_LOW_SPEED_TIME (10 s) and _LIMIT (256 B/s), CURL_CA_BUNDLE,\n"
                 "proxies as curl reads them; S3: AWS_ACCESS_KEY_ID, AWS_SECRET_ACCESS_KEY,\n"
                 "AWS_SESSION_TOKEN, AWS_PROFILE, AWS_REGION, AWS_ENDPOINT_URL,\n"
                 "AWS_NO_SIGN_REQUEST=YES; VOLVIS_HTTP_STATS=1 prints the requests made and\n"
                 "the most in flight at exit (docs/cli.md, \"Remote stores\").\n"
                 "  --cache-dir DIR    keep the bytes fetched from remote stores in DIR\n"
                 "                     (any command; checked by ETag before use, at most\n"
                 "                     $VOLVIS_HTTP_CACHE_MAX bytes, default 1G; the oldest\n"
                 "                     go first; $VOLVIS_HTTP_CACHE_DIR alike)\n"
                 "\n"
                 "Exit status: 0 success, 1 bad input (file, format or render error),\n"
                 "2 bad usage, 130 interrupted. Errors are one line on stderr.\n");
}

/* Takes "--max-memory SIZE" / "--max-memory=SIZE" out of argv and sets the
 * library's memory budget, and "--cache-dir DIR" (the environment's
 * VOLVIS_HTTP_CACHE_DIR). Returns 0, or the exit status of a usage error. */
static int
take_max_memory(int *argc, char **argv) {
    int out = 1;
    for (int i = 1; i < *argc; i++) {
        const char *val = NULL;
        if (!strcmp(argv[i], "--")) {
            while (i < *argc)
                argv[out++] = argv[i++];
            break;
        }
        /* --cache-dir DIR: the remote stores' bytes kept on disk (the transport
         * reads VOLVIS_HTTP_CACHE_DIR at its first use) */
        if (!strcmp(argv[i], "--cache-dir") || !strncmp(argv[i], "--cache-dir=", 12)) {
            const char *dir = argv[i][11] == '=' ? argv[i] + 12 : NULL;
            if (!dir && i + 1 >= *argc)
                return cli_usage_error(NULL, "--cache-dir needs a folder");
            if (!dir)
                dir = argv[++i];
            if (!*dir)
                return cli_usage_error(NULL, "--cache-dir needs a folder");
            setenv("VOLVIS_HTTP_CACHE_DIR", dir, 1);
            continue;
        }
        if (!strcmp(argv[i], "--max-memory")) {
            if (i + 1 >= *argc)
                return cli_usage_error(NULL, "--max-memory needs a size (e.g. 512M, 8G)");
            val = argv[++i];
        } else if (!strncmp(argv[i], "--max-memory=", 13)) {
            val = argv[i] + 13;
        }
        if (!val) {
            argv[out++] = argv[i];
            continue;
        }
        uint64_t bytes = 0;
        if (vv_memory_size_parse(val, &bytes) != VV_OK || bytes == 0)
            return cli_usage_error(NULL, "--max-memory: '%s' is not a size (e.g. 512M, 8G)", val);
        vv_memory_budget_set(bytes);
    }
    *argc = out;
    argv[out] = NULL;
    return 0;
}

int
main(int argc, char **argv) {
    /* a file size limit (ulimit -f) makes a write fail with EFBIG, reported
     * like a full disk, instead of killing the process */
    signal(SIGXFSZ, SIG_IGN);
    int mrc = take_max_memory(&argc, argv);
    if (mrc)
        return mrc;
    if (argc < 2)
        return cli_usage_error(NULL, "missing command");
    const char *cmd = argv[1];
    if (strcmp(cmd, "--help") == 0 || strcmp(cmd, "-h") == 0 || strcmp(cmd, "help") == 0) {
        if (strcmp(cmd, "help") == 0 && argc > 2) {
            const cli_command *c = find_command(argv[2]);
            if (!c)
                return cli_usage_error(NULL, "unknown command '%s'", argv[2]);
            c->usage(stdout);
            return CLI_EXIT_OK;
        }
        usage(stdout);
        return CLI_EXIT_OK;
    }
    if (strcmp(cmd, "--version") == 0 || strcmp(cmd, "-V") == 0 || strcmp(cmd, "version") == 0) {
        printf("volvis %s\n", vv_version());
        return CLI_EXIT_OK;
    }
    const cli_command *c = find_command(cmd);
    if (!c) {
        if (cmd[0] == '-')
            return cli_usage_error(NULL, "unknown option '%s' before the command", cmd);
        return cli_usage_error(NULL, "unknown command '%s'", cmd);
    }
    /* under mpirun: every rank runs the command; only rank 0 prints */
    const int mpi = vv_parallel_launched();
    if (mpi) {
        int rank = 0, size = 1;
        if (vv_parallel_init(&argc, &argv, &rank, &size) != VV_OK)
            return cli_fail(VV_ERR_IO, NULL);
        if (rank > 0) {
            cli_errors_quiet(1);
            if (!freopen("/dev/null", "w", stdout))
                return CLI_EXIT_FAIL;
        }
    }
    int rc = c->run(argc - 1, argv + 1);
    if (fflush(stdout) != 0 && rc == CLI_EXIT_OK) {
        cli_error("cannot write to standard output");
        rc = CLI_EXIT_FAIL;
    }
    if (mpi)
        vv_parallel_finalize();
    return rc;
}

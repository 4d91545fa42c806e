/*
 * libFuzzer harness: whole OME-Zarr stores (src/io/store/zarr_read.c,
 * zarr_pyramid.c): the root .zattrs (multiscales, datasets and their paths,
 * axes, coordinateTransformations, omero), .zgroup, each level's .zarray
 * (shape, chunks, dtype, compressor, fill_value, order, filters,
 * dimension_separator) and the chunk files, as one input.
 *
 * The input is a small container of files: a prelude, then sections, each
 * opened by a line
 *
 *     --FILE <name>--
 *
 * whose bytes (up to the newline before the next such line, or the end)
 * become the file <name> of the store. A name is a relative path of at most
 * 6 components of [A-Za-z0-9._-] ("." and ".." refused), at most 128 bytes:
 * .zgroup, .zattrs, 0/.zarray, 0/0.0.0, 1/0/0/0, ... (its folders are
 * made). A section whose name is refused, or whose file cannot be made (a
 * name that is already a folder), is skipped. The prelude (before the first
 * section) may hold up to three integers: the level, channel and time step
 * asked for (default 0, -1, -1).
 *
 * The store lies in the harness's private folder and is removed after each
 * input. It is read as the library reads one: vv_ome_zarr_read (the level
 * asked for, whole), then vv_open whole and vv_open out of core (the
 * pyramid of zarr_pyramid.c; the format named, so that a folder that is no
 * store never reaches the DICOM row's GDCM), a small box of every level and the proxy of
 * the coarsest read from what opened; in a cache of the harness's own. *
 * Built with FUZZ_STORE_N5 (fuzz_n5.c includes this file), the same
 * container is an N5 store (src/io/store/n5.c): attributes.json of a
 * dataset or of a multiscale group (s0/attributes.json, ...), blocks at
 * 0/0/0, s0/1/0/2, ...; read by vv_n5_read and opened as the N5 format.
 * Built with FUZZ_STORE_PRECOMPUTED (fuzz_precomputed.c), it is a
 * Neuroglancer precomputed volume (src/io/store/precomputed.c): its info
 * and the chunks of its scales (8_8_8/0-16_0-16_0-8, ...).
 */
#include <errno.h>
#include <fcntl.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "fuzz_util.h"
#include "io/store/zarr.h"
#include "volvis/volvis.h"

#if defined FUZZ_STORE_N5
#define STORE_FORMAT VV_FORMAT_N5
#define STORE_READ vv_n5_read
#define STORE_DIR "in.n5"
#elif defined FUZZ_STORE_PRECOMPUTED
#define STORE_FORMAT VV_FORMAT_PRECOMPUTED
#define STORE_READ vv_pc_read
#define STORE_DIR "in.precomputed"
#else
#define STORE_FORMAT VV_FORMAT_OME_ZARR
#define STORE_READ vv_ome_zarr_read
#define STORE_DIR "in.zarr"
#endif

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

/* A budget that keeps a fill-valued volume cheap (as fuzz_scene.c's): every
 * size check still runs, a refusal included. */
#define ZARR_FUZZ_BUDGET ((uint64_t)8 << 20)
#define ZARR_MAX_FILES 64
#define ZARR_MAX_NAME 128

static const char marker[] = "--FILE ";

/* 1 when @p name (NUL-terminated) is a name the container may create. */
static int
safe_name(const char *name) {
    size_t n = strlen(name);
    if (n == 0 || n > ZARR_MAX_NAME || name[0] == '/' || name[n - 1] == '/')
        return 0;
    int parts = 1;
    const char *c = name;
    for (const char *p = name;; p++) {
        if (*p == '/' || *p == '\0') {
            const size_t len = (size_t)(p - c);
            if (len == 0 || (len == 1 && c[0] == '.') || (len == 2 && c[0] == '.' && c[1] == '.'))
                return 0;
            if (*p == '\0')
                break;
            if (++parts > 6)
                return 0;
            c = p + 1;
        } else if (!((*p >= 'a' && *p <= 'z') || (*p >= 'A' && *p <= 'Z') ||
                     (*p >= '0' && *p <= '9') || *p == '.' || *p == '_' || *p == '-')) {
            return 0;
        }
    }
    return 1;
}

/* Writes @p n bytes as file @p name of @p root, its folders made; 0 when it
 * cannot be (a name clashing with a folder or file: the section is skipped). */
static int
put_file(const char *root, const char *name, const uint8_t *b, size_t n) {
    char p[1024];
    snprintf(p, sizeof p, "%s/%s", root, name);
    for (char *s = p + strlen(root) + 1; (s = strchr(s, '/')) != NULL; s++) {
        *s = '\0';
        const int r = mkdir(p, 0700);
        *s = '/';
        if (r != 0 && errno != EEXIST)
            return 0;
    }
    const int fd = open(p, O_WRONLY | O_CREAT | O_TRUNC, 0600);
    if (fd < 0)
        return 0;
    size_t done = 0;
    while (done < n) {
        const ssize_t w = write(fd, b + done, n - done);
        if (w <= 0) {
            perror("fuzz: writing a store's file");
            abort(); /* the machine, not the input */
        }
        done += (size_t)w;
    }
    close(fd);
    return 1;
}

/* The first "--FILE " at a line's start at or after @p from, or @p size. */
static size_t
next_marker(const uint8_t *data, size_t size, size_t from) {
    const size_t ml = sizeof marker - 1;
    for (size_t i = from; i + ml <= size; i++)
        if ((i == 0 || data[i - 1] == '\n') && !memcmp(data + i, marker, ml))
            return i;
    return size;
}

/* The store of the input at @p root; the prelude's integers into ask[3]. */
static void
build_store(const char *root, const uint8_t *data, size_t size, int ask[3]) {
    if (mkdir(root, 0700) != 0) {
        perror("fuzz: mkdir store");
        abort();
    }
    size_t at = next_marker(data, size, 0);
    char pre[64];
    const size_t np = at < sizeof pre - 1 ? at : sizeof pre - 1;
    memcpy(pre, data, np);
    pre[np] = '\0';
    int v[3] = {0, -1, -1};
    const int got = sscanf(pre, "%d %d %d", &v[0], &v[1], &v[2]);
    for (int k = 0; k < 3; k++) /* small: a level, channel or step past the store's is a check */
        ask[k] = k < got && v[k] >= -1 && v[k] <= 20 ? v[k] : (k ? -1 : 0);
    for (int files = 0; at < size && files < ZARR_MAX_FILES; files++) {
        const size_t name0 = at + sizeof marker - 1;
        size_t eol = name0;
        while (eol < size && data[eol] != '\n')
            eol++;
        const size_t body = eol < size ? eol + 1 : size;
        size_t next = next_marker(data, size, body);
        /* the newline before the next marker is the separator's */
        const size_t end = next < size && next > body ? next - 1 : next;
        char name[ZARR_MAX_NAME + 3];
        const size_t nl = eol - name0;
        if (nl >= 3 && nl <= ZARR_MAX_NAME + 2 && data[eol - 1] == '-' && data[eol - 2] == '-') {
            memcpy(name, data + name0, nl - 2);
            name[nl - 2] = '\0';
            if (!memchr(data + name0, '\0', nl - 2) && safe_name(name))
                put_file(root, name, data + body, end > body ? end - body : 0);
        }
        at = next;
    }
}

static void
open_store(const char *root, vv_open_mode mode, const int ask[3], vv_cache *cache) {
    vv_open_options oo;
    vv_open_options_init(&oo);
    oo.mode = mode;
    /* the format named: a folder that is no store is not handed to the
     * DICOM row (GDCM, a third party's, the sandbox's: fuzz_dicom) */
    oo.load.format = STORE_FORMAT;
    oo.load.level = ask[0];
    oo.load.channel = ask[1];
    oo.load.time = ask[2];
    oo.cache = cache;
    vv_opened o;
    memset(&o, 0, sizeof o);
    const vv_status st = vv_open(&o, root, &oo);
    fuzz_check_status(st);
    if (st != VV_OK)
        return;
    if (o.kind != VV_DATA_VOLUME || !o.source)
        __builtin_trap(); /* a store holds a volume */
    fuzz_read_source(o.source);
    vv_opened_clear(&o);
}

int
LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    static vv_cache *cache; /* one budget for every input, as a process has */
    if (!cache) {
        vv_memory_budget_set(ZARR_FUZZ_BUDGET);
        if (vv_cache_new(&cache, ZARR_FUZZ_BUDGET) != VV_OK)
            __builtin_trap();
    }
    char root[512];
    snprintf(root, sizeof root, "%s/" STORE_DIR, fuzz_dir());
    fuzz_rm_tree(root); /* whatever a previous input left */
    int ask[3];
    build_store(root, data, size, ask);
    vv_load_options lo;
    vv_load_options_init(&lo);
    vv_load_info info;
    memset(&info, 0, sizeof info);
    lo.level = ask[0];
    lo.channel = ask[1];
    lo.time = ask[2];
    lo.info = &info;
    vv_volume *v = NULL;
    const vv_status st = STORE_READ(&v, root, &lo);
    fuzz_check_status(st);
    if (st == VV_OK) {
        if (!memchr(info.channel_name, '\0', sizeof info.channel_name))
            __builtin_trap(); /* the name is terminated */
        fuzz_check_volume(v);
    }
    open_store(root, VV_OPEN_WHOLE, ask, cache);
    open_store(root, VV_OPEN_OUT_OF_CORE, ask, cache);
    fuzz_rm_tree(root);
    return 0;
}

/*
 * The format table (after Teem's nrrd/format.c): one record per format of
 * every kind -- volumes, pyramids, grids, meshes -- defined in the
 * format's own file (include/volvis/sys/format.h says what a record holds),
 * listed once below. A format's id (vv_format) is its row. Detection (one
 * probe of a file's head, asked of every row), the names --format takes,
 * vv_open, loading and saving (volume_io.c, open.c) and the lists in
 * --help all read this table.
 */
#include <ctype.h>
#include <dirent.h>
#include <errno.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>

#include <zlib.h>

#include "core/internal.h"
#include "io/io_internal.h"
#include "io/store/bytesrc.h"
#include "io/transport.h"
#include "volvis/io.h"
#include "volvis/sys/format.h"

/* The table: one row per format, in the order of the vv_format ids (the
 * named volume formats first, then grids and meshes). Adding a format: its
 * file defines vv_format_<name>, and one X(<name>) row goes here. */
#define VV_FORMAT_TABLE(X)                                                                         \
    X(slc)                                                                                         \
    X(nrrd)                                                                                        \
    X(nifti)                                                                                       \
    X(mhd)                                                                                         \
    X(vtk)                                                                                         \
    X(raw)                                                                                         \
    X(tiff)                                                                                        \
    X(dicom)                                                                                       \
    X(vti)                                                                                         \
    X(ome_zarr)                                                                                    \
    X(hdf5)                                                                                        \
    X(vvb)                                                                                         \
    X(bdv_xml)                                                                                     \
    X(n5)                                                                                          \
    X(precomputed)                                                                                 \
    X(vtk_grid)                                                                                    \
    X(vtu)                                                                                         \
    X(dx)                                                                                          \
    X(plot3d)                                                                                      \
    X(netcdf)                                                                                      \
    X(mesh)

#define DECLARE(name) extern const vv_format_record vv_format_##name;
VV_FORMAT_TABLE(DECLARE)
#undef DECLARE

/* The rows built in, then those vv_format_register adds (at most
 * VV_FORMATS_REGISTERED_MAX): a row's slot is written before the count that
 * shows it is raised, so readers without the lock see whole rows only. */
#define ROW(name) &vv_format_##name,
#define ONE(name) +1
enum { N_BUILT_IN = 0 VV_FORMAT_TABLE(ONE) };
static const vv_format_record *table[N_BUILT_IN + VV_FORMATS_REGISTERED_MAX] = {
    VV_FORMAT_TABLE(ROW)};
#undef ONE
#undef ROW
static atomic_int n_rows = N_BUILT_IN;
static pthread_mutex_t register_lock = PTHREAD_MUTEX_INITIALIZER;

#define N_FORMATS atomic_load_explicit(&n_rows, memory_order_acquire)

const vv_format_record *const *
vv_format_table(int *n) {
    if (n)
        *n = N_FORMATS;
    return table;
}

const vv_format_record *
vv_format_record_of(vv_format f) {
    return (int)f >= 1 && (int)f <= N_FORMATS ? table[(int)f - 1] : NULL;
}

vv_format
io_format_id(const vv_format_record *r) {
    const int n = N_FORMATS;
    for (int i = 0; r && i < n; i++)
        if (table[i] == r)
            return (vv_format)(i + 1);
    return VV_FORMAT_UNKNOWN;
}

int
io_format_built_in(const vv_format_record *r) {
    const vv_format f = io_format_id(r);
    return f != VV_FORMAT_UNKNOWN && (int)f <= N_BUILT_IN;
}

/* 1 when @p name is a name or an alias of row @p r. */
static int
names(const vv_format_record *r, const char *name) {
    if (!strcasecmp(name, r->name))
        return 1;
    for (const char *const *a = r->aliases; a && *a; a++)
        if (!strcasecmp(name, *a))
            return 1;
    return 0;
}

vv_status
vv_format_register(const vv_format_record *row, vv_format *id) {
    if (!row || !row->name || !row->title)
        return vv_error_set(VV_ERR_INVALID, "format register: a row needs a name and a title");
    if (row->version != 2 && row->version != VV_FORMAT_RECORD_VERSION)
        return vv_error_set(VV_ERR_UNSUPPORTED,
                            "format register: %s: record version %d (this library reads %d)",
                            row->name, row->version, VV_FORMAT_RECORD_VERSION);
    const int volume = row->read || row->write || row->write_boxes || row->open_store ||
                       row->raw_layout || row->open_bricks;
    const int reads = row->holds == VV_DATA_VOLUME ? volume
                      : row->holds == VV_DATA_GRID ? row->read_grid || row->write_grid
                      : row->holds == VV_DATA_MESH ? row->read_mesh != NULL
                                                   : -1;
    if (reads < 0)
        return vv_error_set(VV_ERR_INVALID, "format register: %s: holds kind %d", row->name,
                            (int)row->holds);
    if (!reads)
        return vv_error_set(VV_ERR_INVALID,
                            "format register: %s: the row neither reads nor writes what it holds",
                            row->name);
    if (row->flags & VV_FORMAT_FLAG_THIRD_PARTY)
        return vv_error_set(VV_ERR_UNSUPPORTED,
                            "format register: %s: a row added at run time cannot be read in the "
                            "reader sandbox (volvis-reader has the built-in rows only); leave "
                            "VV_FORMAT_FLAG_THIRD_PARTY off",
                            row->name);
    pthread_mutex_lock(&register_lock);
    const int n = atomic_load(&n_rows);
    vv_status s = VV_OK;
    for (int i = 0; i < n && s == VV_OK; i++) {
        int clash = names(table[i], row->name);
        for (const char *const *a = row->aliases; !clash && a && *a; a++)
            clash = names(table[i], *a);
        if (clash)
            s = vv_error_set(VV_ERR_INVALID, "format register: %s: the name is format %s's",
                             row->name, table[i]->name);
    }
    if (s == VV_OK && n >= (int)(sizeof table / sizeof table[0]))
        s = vv_error_set(VV_ERR_LIMIT, "format register: %s: over %d rows registered", row->name,
                         VV_FORMATS_REGISTERED_MAX);
    if (s == VV_OK) {
        table[n] = row;
        atomic_store_explicit(&n_rows, n + 1, memory_order_release);
        if (id)
            *id = (vv_format)(n + 1);
    }
    pthread_mutex_unlock(&register_lock);
    return s;
}

const char *const *
vv_format_record_write_extensions(const vv_format_record *f) {
    if (!f || !(f->write || f->write_grid))
        return NULL;
    return f->write_extensions ? f->write_extensions : f->extensions;
}

int
vv_format_count(void) {
    return N_FORMATS;
}

/* The record of id @p f, or NULL. */
static const vv_format_record *
record(vv_format f) {
    return vv_format_record_of(f);
}

const char *
vv_format_name(vv_format f) {
    if (f == VV_FORMAT_AUTO)
        return "auto";
    const vv_format_record *r = record(f);
    return r ? r->name : "unknown";
}

vv_status
vv_format_parse(const char *name, vv_format *out) {
    if (!name || !out)
        return vv_error_set(VV_ERR_INVALID, "format: NULL argument");
    if (!strcasecmp(name, "auto")) {
        *out = VV_FORMAT_AUTO;
        return VV_OK;
    }
    const int n = N_FORMATS;
    for (int i = 0; i < n; i++) {
        if (names(table[i], name)) {
            *out = (vv_format)(i + 1);
            return VV_OK;
        }
    }
    char list[768] = "auto";
    for (int i = 0; i < n; i++) {
        size_t k = strlen(list);
        snprintf(list + k, sizeof list - k, "%s%s", i + 1 < n ? ", " : " or ", table[i]->name);
    }
    return vv_error_set(VV_ERR_INVALID, "unknown format \"%s\" (expected %s)", name, list);
}

/* ---- probing ------------------------------------------------------------- */

int
vv_format_path_has_ext(const char *path, const char *ext) {
    const char *base = vv_path_basename(path);
    size_t n = strlen(base), m = strlen(ext);
    return n > m + 1 && base[n - m - 1] == '.' && strcasecmp(base + n - m, ext) == 0;
}

int
vv_format_probe_fill(vv_format_probe *p, const char *path, unsigned char *buf, char *text) {
    memset(p, 0, sizeof *p);
    p->path = path;
    p->head = buf;
    p->text = text;
    text[0] = '\0';
    struct stat st;
    if (stat(path, &st) == 0 && S_ISDIR(st.st_mode)) {
        p->is_dir = 1;
        return 0;
    }
    FILE *f = fopen(path, "rb");
    if (!f)
        return errno ? errno : EIO;
    size_t n = fread(buf, 1, VV_FORMAT_PROBE_BYTES, f);
    int err = ferror(f) ? EIO : 0;
    fclose(f);
    if (n >= 2 && buf[0] == 0x1f && buf[1] == 0x8b) {
        p->gzip = 1;
        gzFile g = gzopen(path, "rb");
        int r = g ? gzread(g, buf, VV_FORMAT_PROBE_BYTES) : 0;
        if (g)
            gzclose(g);
        n = r > 0 ? (size_t)r : 0;
    }
    p->n = n;
    for (size_t i = 0; i < n; i++)
        text[i] = buf[i] ? (char)buf[i] : ' ';
    text[n] = '\0';
    return err;
}

int
vv_format_folder_any(const char *path,
                     int (*match)(const char *entry, const char *name, int is_dir, void *ctx),
                     void *ctx) {
    DIR *d = opendir(path);
    if (!d)
        return 0;
    int found = 0, looked = 0;
    struct dirent *e;
    while (!found && looked < 4096 && (e = readdir(d))) {
        if (e->d_name[0] == '.')
            continue;
        size_t len = strlen(path) + strlen(e->d_name) + 2;
        char *p = malloc(len);
        if (!p)
            break;
        snprintf(p, len, "%s/%s", path, e->d_name);
        struct stat st;
        if (stat(p, &st) == 0) {
            if (S_ISDIR(st.st_mode)) {
                found = match(p, e->d_name, 1, ctx);
            } else if (S_ISREG(st.st_mode)) {
                looked++;
                found = match(p, e->d_name, 0, ctx);
            }
        }
        free(p);
    }
    closedir(d);
    return found;
}

/* The first format of rows @p first to @p end - 1 holding @p kind (-1:
 * any), in table order, whose looks_like says yes at @p deep; a
 * gzip-compressed file is asked of the formats read compressed only. */
static vv_format
ask_rows(const vv_format_probe *p, int kind, int deep, int first, int end) {
    for (int i = first; i < end; i++) {
        const vv_format_record *r = table[i];
        if (!r->looks_like || (p->gzip && !(r->flags & VV_FORMAT_FLAG_GZIP)) ||
            (kind >= 0 && (int)r->holds != kind))
            continue;
        if (r->looks_like(p, deep))
            return (vv_format)(i + 1);
    }
    return VV_FORMAT_UNKNOWN;
}

vv_format
vv_format_detect_kind(const char *path, int kind, int deep) {
    if (!path)
        return VV_FORMAT_UNKNOWN;
    /* a URL is a remote store (src/io/store/bytesrc.h): the Zarr row,
     * which tells v2 from v3 by the objects it fetches; nothing local is
     * looked at */
    if (bs_is_url(path)) {
        if (kind >= 0 && kind != VV_DATA_VOLUME)
            return VV_FORMAT_UNKNOWN;
        /* Neuroglancer's precomputed:// and n5:// name their rows */
        const char *row = bs_url_format(path) ? bs_url_format(path) : "zarr";
        for (int i = 0; i < N_BUILT_IN; i++)
            if (!strcmp(table[i]->name, row))
                return (vv_format)(i + 1);
        return VV_FORMAT_UNKNOWN;
    }
    unsigned char buf[VV_FORMAT_PROBE_BYTES + 1];
    char text[VV_FORMAT_PROBE_BYTES + 1];
    vv_format_probe p;
    int err = vv_format_probe_fill(&p, path, buf, text);
    /* signatures, every row; then the deep tests, the registered rows'
     * first (io_detect_registered asks them alone where the sandbox asks
     * the built-in rows') */
    vv_format f = ask_rows(&p, kind, 0, 0, N_FORMATS);
    if (f != VV_FORMAT_UNKNOWN || err || !deep)
        return f;
    f = ask_rows(&p, kind, 1, N_BUILT_IN, N_FORMATS);
    return f != VV_FORMAT_UNKNOWN ? f : ask_rows(&p, kind, 1, 0, N_BUILT_IN);
}

vv_format
io_detect_registered(const char *path, int kind) {
    if (!path || N_FORMATS == N_BUILT_IN)
        return VV_FORMAT_UNKNOWN;
    unsigned char buf[VV_FORMAT_PROBE_BYTES + 1];
    char text[VV_FORMAT_PROBE_BYTES + 1];
    vv_format_probe p;
    if (vv_format_probe_fill(&p, path, buf, text))
        return VV_FORMAT_UNKNOWN;
    return ask_rows(&p, kind, 1, N_BUILT_IN, N_FORMATS);
}

vv_format
vv_format_detect(const char *path) {
    return vv_format_detect_kind(path, -1, 1);
}

/*
 * DICOM series: finding the files (a folder's, recursively, or a
 * DICOMDIR's), reading their headers, grouping them by Series Instance UID
 * and listing the series; the entry points and the format record. One
 * series into a volume (ordering the slices along the slice normal,
 * checking the spacing, the pixel values) is dicom_volume.c's; the scan
 * both share, dicom_scan.h's. Parsing and decoding are GDCM's, through the
 * C++ shim dicom_gdcm.cpp (see dicom.h); without GDCM the entry points say
 * VV_ERR_UNSUPPORTED.
 *
 * Headers are read in parallel (OpenMP, one GDCM reader per file).
 */
#include <dirent.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>

#include "core/internal.h"
#include "io/io_internal.h"
#include "io/prescan.h"
#include "io/transport.h"
#include "io/volume/dicom.h"
#include "io/volume/dicom_scan.h"
#include "volvis/io.h"
#include "volvis/sys/format.h"

int
vv_dicom_sniff(const char *path) {
    unsigned char h[136];
    FILE *f = fopen(path, "rb");
    if (!f)
        return 0;
    size_t n = fread(h, 1, sizeof h, f);
    fclose(f);
    if (n >= 132 && !memcmp(h + 128, "DICM", 4))
        return 1;
    if (n < 8)
        return 0;
    /* no preamble: the first element of group 0002 or 0008, either byte order,
     * with an explicit VR (two upper-case letters) or a short implicit length */
    int le = (h[0] == 0x08 || h[0] == 0x02) && h[1] == 0 && h[3] == 0;
    int be = h[0] == 0 && (h[1] == 0x08 || h[1] == 0x02) && h[2] == 0;
    if (!le && !be)
        return 0;
    if (h[4] >= 'A' && h[4] <= 'Z' && h[5] >= 'A' && h[5] <= 'Z')
        return 1;
    uint32_t len =
        le ? (uint32_t)h[4] | (uint32_t)h[5] << 8 | (uint32_t)h[6] << 16 | (uint32_t)h[7] << 24
           : (uint32_t)h[7] | (uint32_t)h[6] << 8 | (uint32_t)h[5] << 16 | (uint32_t)h[4] << 24;
    return le && len > 0 && len <= 256 && (len % 2) == 0;
}

#ifndef VV_HAVE_GDCM

vv_status
io_dicom_list_local(vv_dicom_series **out, int *n, const char *path) {
    if (out)
        *out = NULL;
    if (n)
        *n = 0;
    return vv_error_set(VV_ERR_UNSUPPORTED,
                        "dicom: %s: this build has no DICOM support (GDCM, libgdcm-dev)",
                        path ? path : "");
}

vv_status
vv_dicom_read(vv_volume **out, const char *path, int series, int channel) {
    (void)series;
    (void)channel;
    if (out)
        *out = NULL;
    return io_dicom_list_local(NULL, NULL, path);
}

vv_status
vv_dicom_read_files(vv_volume **out, const char *const *files, int n, int series, int channel) {
    (void)series;
    (void)channel;
    if (out)
        *out = NULL;
    return io_dicom_list_local(NULL, NULL, n > 0 && files ? files[0] : "");
}

static vv_status
dicom_read_at(vv_volume **out, const char *path, int series, int channel, int time,
              vv_load_info *info) {
    (void)time;
    (void)info;
    return vv_dicom_read(out, path, series, channel);
}

#else

#define MAX_FILES 200000
#define MAX_DEPTH 8

/* ---- finding files --------------------------------------------------------- */

typedef struct file_list {
    char **v;
    int n, cap;
} file_list;

static void
list_free(file_list *l) {
    for (int i = 0; i < l->n; i++)
        free(l->v[i]);
    free(l->v);
    memset(l, 0, sizeof *l);
}

static vv_status
list_add(file_list *l, const char *path) {
    if (l->n >= MAX_FILES)
        return vv_error_set(VV_ERR_LIMIT, "more than %d files", MAX_FILES);
    if (l->n == l->cap) {
        int cap = l->cap ? 2 * l->cap : 256;
        char **v = realloc(l->v, (size_t)cap * sizeof *v);
        if (!v)
            return vv_error_set(VV_ERR_NOMEM, "out of memory listing files");
        l->v = v;
        l->cap = cap;
    }
    if (!(l->v[l->n] = vv_strdup(path)))
        return vv_error_set(VV_ERR_NOMEM, "out of memory listing files");
    l->n++;
    return VV_OK;
}

static int
cmp_str(const void *a, const void *b) {
    return strcmp(*(const char *const *)a, *(const char *const *)b);
}

static vv_status
scan_folder(file_list *l, const char *dir, int depth) {
    DIR *d = opendir(dir);
    if (!d)
        return vv_error_set(VV_ERR_IO, "cannot open the folder %s: %s", dir, strerror(errno));
    vv_status s = VV_OK;
    struct dirent *e;
    while (s == VV_OK && (e = readdir(d))) {
        if (e->d_name[0] == '.')
            continue;
        size_t len = strlen(dir) + strlen(e->d_name) + 2;
        char *p = malloc(len);
        if (!p) {
            s = vv_error_set(VV_ERR_NOMEM, "out of memory listing files");
            break;
        }
        snprintf(p, len, "%s/%s", dir, e->d_name);
        struct stat st;
        if (stat(p, &st) == 0) {
            if (S_ISDIR(st.st_mode) && depth < MAX_DEPTH)
                s = scan_folder(l, p, depth + 1);
            else if (S_ISREG(st.st_mode) && strcasecmp(e->d_name, "DICOMDIR") != 0)
                s = list_add(l, p);
        }
        free(p);
    }
    closedir(d);
    return s;
}

vv_status
vv_dicom_prescan(const char *path) {
    char err[512] = "";
    if (vv_dcm_prescan(path, err, sizeof err) != 0)
        return vv_error_set(VV_ERR_FORMAT, "dicom: %s: %s", vv_path_basename(path), err);
    return VV_OK;
}

/* The candidate files of @p path: a folder's files (recursively), a
 * DICOMDIR's references, or the file itself. */
static vv_status
collect(file_list *l, const char *path) {
    memset(l, 0, sizeof *l);
    struct stat st;
    if (stat(path, &st) != 0)
        return vv_error_set(VV_ERR_IO, "cannot open: %s", strerror(errno));
    vv_status s;
    if (S_ISDIR(st.st_mode)) {
        s = scan_folder(l, path, 0);
        if (s == VV_OK && l->n > 1)
            qsort(l->v, (size_t)l->n, sizeof *l->v, cmp_str);
        return s;
    }
    char **refs = NULL;
    int nrefs = 0;
    char err[256] = "";
    int r = vv_dcm_dicomdir_files(path, &refs, &nrefs, err, sizeof err);
    if (r < 0) /* a DICOMDIR's or any file's header: the message says which element */
        return vv_error_set(VV_ERR_FORMAT, "%s", err);
    if (r == 0)
        return list_add(l, path);
    s = VV_OK;
    for (int i = 0; i < nrefs; i++) {
        if (s == VV_OK)
            s = list_add(l, refs[i]);
        free(refs[i]);
    }
    free(refs);
    return s;
}

/* ---- headers and series ---------------------------------------------------- */

static void
scan_free(dicom_scan *sc) {
    for (int i = 0; i < sc->n; i++) {
        free(sc->f[i].path);
        free(sc->f[i].frame_ipp);
    }
    free(sc->f);
    free(sc->order);
    free(sc->start);
    memset(sc, 0, sizeof *sc);
}

static const vv_dcm_file *sort_files;

static int
cmp_series(const void *a, const void *b) {
    const vv_dcm_file *x = &sort_files[*(const int *)a], *y = &sort_files[*(const int *)b];
    if (x->series_number != y->series_number)
        return x->series_number < y->series_number ? -1 : 1;
    int c = strcmp(x->series_uid, y->series_uid);
    if (c)
        return c;
    return strcmp(x->path, y->path);
}

/* Reads every candidate's header; groups the images by series. */
static vv_status
scan_files(dicom_scan *sc, char **paths, int n) {
    memset(sc, 0, sizeof *sc);
    sc->looked = n;
    vv_dcm_file *f = calloc((size_t)(n > 0 ? n : 1), sizeof *f);
    int *kind = calloc((size_t)(n > 0 ? n : 1), sizeof *kind);
    char(*errs)[256] = calloc((size_t)(n > 0 ? n : 1), sizeof *errs);
    if (!f || !kind || !errs) {
        free(f);
        free(kind);
        free(errs);
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    }
    vv_dcm_init();
#pragma omp parallel for schedule(dynamic, 4)
    for (int i = 0; i < n; i++)
        kind[i] = vv_dcm_read_header(paths[i], &f[i], errs[i], sizeof errs[i]);
    vv_status s = VV_OK;
    int m = 0;
    for (int i = 0; i < n; i++) {
        if (kind[i] < 0 && s == VV_OK)
            s = vv_error_set(VV_ERR_FORMAT, "%s: %s", paths[i], errs[i]);
        if (kind[i] == 1) {
            f[m] = f[i];
            f[m].path = vv_strdup(paths[i]);
            if (!f[m].path && s == VV_OK)
                s = vv_error_set(VV_ERR_NOMEM, "out of memory");
            if (m != i)
                f[i].frame_ipp = NULL;
            m++;
        } else {
            free(f[i].frame_ipp);
            f[i].frame_ipp = NULL;
        }
    }
    free(kind);
    free(errs);
    sc->f = f;
    sc->n = m;
    if (s != VV_OK)
        return s;
    if (m == 0)
        return vv_error_set(VV_ERR_FORMAT, "no DICOM images (%d file%s looked at)", n,
                            n == 1 ? "" : "s");
    sc->order = malloc((size_t)m * sizeof *sc->order);
    sc->start = malloc((size_t)(m + 1) * sizeof *sc->start);
    if (!sc->order || !sc->start)
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    for (int i = 0; i < m; i++)
        sc->order[i] = i;
    sort_files = f; /* qsort has no context argument in C11 */
    qsort(sc->order, (size_t)m, sizeof *sc->order, cmp_series);
    sort_files = NULL;
    for (int i = 0; i < m; i++)
        if (i == 0 || strcmp(f[sc->order[i]].series_uid, f[sc->order[i - 1]].series_uid) != 0 ||
            f[sc->order[i]].series_number != f[sc->order[i - 1]].series_number)
            sc->start[sc->n_series++] = i;
    sc->start[sc->n_series] = m;
    return VV_OK;
}

static vv_status
scan_path(dicom_scan *sc, const char *path) {
    memset(sc, 0, sizeof *sc);
    file_list l;
    vv_status s = collect(&l, path);
    if (s == VV_OK)
        s = scan_files(sc, l.v, l.n);
    list_free(&l);
    return s;
}

static void
describe(const dicom_scan *sc, int si, vv_dicom_series *d) {
    memset(d, 0, sizeof *d);
    const vv_dcm_file *f = &sc->f[sc->order[sc->start[si]]];
    snprintf(d->uid, sizeof d->uid, "%s", f->series_uid);
    snprintf(d->description, sizeof d->description, "%s", f->series_desc);
    snprintf(d->modality, sizeof d->modality, "%s", f->modality);
    snprintf(d->study_description, sizeof d->study_description, "%s", f->study_desc);
    snprintf(d->study_date, sizeof d->study_date, "%s", f->study_date);
    snprintf(d->patient_name, sizeof d->patient_name, "%s", f->patient_name);
    snprintf(d->patient_id, sizeof d->patient_id, "%s", f->patient_id);
    snprintf(d->first_file, sizeof d->first_file, "%s", f->path);
    d->number = f->series_number;
    d->dims[0] = f->cols;
    d->dims[1] = f->rows;
    d->n_files = sc->start[si + 1] - sc->start[si];
    long frames = 0;
    for (int i = sc->start[si]; i < sc->start[si + 1]; i++)
        frames += sc->f[sc->order[i]].frames;
    d->time_steps = dicom_series_time_steps(sc, si, frames);
    frames /= d->time_steps;
    d->dims[2] = frames > 1 << 30 ? 1 << 30 : (int)frames;
}

vv_status
io_dicom_list_local(vv_dicom_series **out, int *n, const char *path) {
    if (!out || !n || !path)
        return vv_error_set(VV_ERR_INVALID, "dicom: NULL argument");
    *out = NULL;
    *n = 0;
    dicom_scan sc;
    vv_status s = scan_path(&sc, path);
    if (s == VV_OK) {
        *out = calloc((size_t)sc.n_series, sizeof **out);
        if (!*out) {
            s = vv_error_set(VV_ERR_NOMEM, "out of memory");
        } else {
            for (int i = 0; i < sc.n_series; i++)
                describe(&sc, i, &(*out)[i]);
            *n = sc.n_series;
        }
    }
    scan_free(&sc);
    if (s != VV_OK)
        return vv_error_prefix(s, "dicom: %s", path);
    return VV_OK;
}

/* ---- reading a series -------------------------------------------------------- */

static vv_status
read_scanned(vv_volume **out, dicom_scan *sc, int series, int channel, int time,
             vv_load_info *info) {
    if (series < 0 || series > sc->n_series)
        return vv_error_set(VV_ERR_INVALID, "series %d asked, there %s %d", series,
                            sc->n_series == 1 ? "is" : "are", sc->n_series);
    if (series == 0 && sc->n_series > 1)
        return vv_error_set(VV_ERR_INVALID,
                            "%d series (mixed series): choose one with --series N (1 to %d; "
                            "'volvis info' lists them)",
                            sc->n_series, sc->n_series);
    return dicom_read_series(out, sc, series ? series - 1 : 0, channel, time, info);
}

/* Prefixes "dicom: PATH" to the error of @p s, or only "dicom" when the
 * message already begins with PATH (a single file names itself). */
static vv_status
prefix_path(vv_status s, const char *path) {
    const char *msg = vv_error_message();
    if (msg && strncmp(msg, path, strlen(path)) == 0)
        return vv_error_prefix(s, "dicom");
    return vv_error_prefix(s, "dicom: %s", path);
}

/* vv_dicom_read with a time step and the file's axes (vv_load_info). */
static vv_status
dicom_read_at(vv_volume **out, const char *path, int series, int channel, int time,
              vv_load_info *info) {
    if (!out || !path)
        return vv_error_set(VV_ERR_INVALID, "dicom: NULL argument");
    *out = NULL;
    dicom_scan sc;
    vv_status s = scan_path(&sc, path);
    if (s == VV_OK)
        s = read_scanned(out, &sc, series, channel, time, info);
    scan_free(&sc);
    if (s != VV_OK)
        return prefix_path(s, path);
    return VV_OK;
}

vv_status
vv_dicom_read(vv_volume **out, const char *path, int series, int channel) {
    return dicom_read_at(out, path, series, channel, 0, NULL);
}

vv_status
vv_dicom_read_files(vv_volume **out, const char *const *files, int n, int series, int channel) {
    if (!out || !files || n < 1)
        return vv_error_set(VV_ERR_INVALID, "dicom: no files");
    *out = NULL;
    dicom_scan sc;
    vv_status s = scan_files(&sc, (char **)files, n);
    if (s == VV_OK)
        s = read_scanned(out, &sc, series, channel, 0, NULL);
    scan_free(&sc);
    if (s != VV_OK)
        return vv_error_prefix(s, "dicom: %d files", n);
    return VV_OK;
}

#endif

/* ---- the format record ------------------------------------------------------ */

/* A DICOMDIR or a DICOM file in a folder, or (at depth 0) in a subfolder:
 * ctx[0] the depth, ctx[1] 1 when a file without the preamble counts. */
static int
dicom_entry(const char *entry, const char *name, int is_dir, void *ctx) {
    const int *c = ctx;
    if (is_dir) {
        int deeper[2] = {c[0] + 1, c[1]};
        return c[0] < 1 && vv_format_folder_any(entry, dicom_entry, deeper);
    }
    return !strcasecmp(name, "DICOMDIR") ||
           vv_format_detect_kind(entry, -1, c[1]) == VV_FORMAT_DICOM;
}

/* "DICM" after the 128-byte preamble, a folder holding such a file or a
 * DICOMDIR; at @p deep 1 a file without the preamble (old ACR-NEMA style)
 * whose first element reads as DICOM, and a folder of those (asked after
 * every format's signature, so that the chunk of a store -- a precomputed
 * volume's, an N5 dataset's -- whose first bytes read as an element does
 * not make its folder a series). */
static int
dicom_looks_like(const vv_format_probe *p, int deep) {
    if (p->is_dir)
        return vv_format_folder_any(p->path, dicom_entry, (int[2]){0, deep});
    if (!deep)
        return p->n >= 132 && !memcmp(p->head + 128, "DICM", 4);
    return p->n > 0 && vv_dicom_sniff(p->path);
}

static vv_status
dicom_read_record(vv_volume **out, const char *path, const vv_load_options *opt) {
    return dicom_read_at(out, path, opt->series, opt->channel, opt->time, opt->info);
}

static const char *const dicom_extensions[] = {"dcm", NULL};
static const char *const dicom_aliases[] = {"dcm", NULL};

const vv_format_record vv_format_dicom = {
    .version = VV_FORMAT_RECORD_VERSION,
    .name = "dicom",
    .title = "DICOM",
    .extensions = dicom_extensions,
    .aliases = dicom_aliases,
    .doc = "DICOM series through GDCM: folders, DICOMDIR, multi-frame, compressed syntaxes",
    .flags = VV_FORMAT_FLAG_THIRD_PARTY | VV_FORMAT_FLAG_FOLDER,
    .looks_like = dicom_looks_like,
    .read = dicom_read_record,
};

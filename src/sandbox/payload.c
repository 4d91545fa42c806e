/*
 * Results in sealed memfds (src/sandbox; the wire in sandbox_internal.h).
 * The reader's side: its volumes' voxels are made in memfds (its
 * allocator), meshes and grids are laid out in one, and each is sealed
 * before it is handed over, its own mapping removed first so that nothing
 * can change the bytes once the parent has them. The parent's side: every
 * decoder checks what it was given -- sizes against the memfd, the seals,
 * a finite geometry, every index and offset -- before it believes it; a
 * volume is mapped privately (no copy), or, asked with peek, copied out of
 * the reader's memory (process_vm_readv) with no memfd at all; meshes,
 * grids and listings are copied first. Nothing a reader sends is trusted (fuzzed by
 * tests/fuzz/fuzz_sandbox.c through sbx_take_message).
 */
#define _GNU_SOURCE
#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <sys/uio.h>
#include <unistd.h>

#include "core/grid_internal.h"
#include "core/internal.h"
#include "sandbox/sandbox_internal.h"

void
sbx_printable(char *s, size_t cap) {
    if (!cap)
        return;
    s[cap - 1] = '\0';
    for (char *c = s; *c; c++) /* one line of printable text */
        if ((unsigned char)*c < 0x20 || *c == 0x7f)
            *c = ' ';
}

/*
 * madvise(@p advice) over [@p p, @p p + @p len) in 8 MiB pieces on the
 * library's threads: the kernel populates or zaps the page tables of
 * different pieces in parallel (both take the mapping lock shared), where
 * one call does it on one core; a 150 MiB volume is 38 400 pages. @p p is
 * page-aligned. Used by both sides: the reader's memfd, the parent's
 * mapping of it. Advice the kernel refuses (MADV_POPULATE_* before Linux
 * 5.14) is ignored: the pages are then faulted in use.
 */
void
sbx_madvise_parallel(void *p, size_t len, int advice) {
    const size_t piece = (size_t)8 << 20;
    const int64_t n = (int64_t)((len + piece - 1) / piece);
#pragma omp parallel for schedule(static) if (n > 1)
    for (int64_t i = 0; i < n; i++) {
        size_t off = (size_t)i * piece;
        (void)madvise((char *)p + off, len - off < piece ? len - off : piece, advice);
    }
}

/*
 * [@p p, @p p + @p bytes) in pieces of @p piece bytes (a multiple of the
 * voxel size) on the library's threads: each piece first taken by
 * @p take (0, or an errno: the first one returned, and the other pieces
 * stop taking), then its voxels of type @p type measured into @p range
 * (vv_range_accumulate) on the same thread, while the piece is in its
 * core's cache. The parent's one pass over a volume it got from a reader:
 * the range it trusts no reader for, in the pass that makes the voxels
 * its own.
 */
static int
take_and_range(unsigned char *p, size_t bytes, size_t piece, vv_voxel_type type,
               int (*take)(void *ctx, unsigned char *at, size_t off, size_t len), void *ctx,
               double range[2]) {
    const size_t es = vv_voxel_type_size(type);
    const int64_t n = (int64_t)((bytes + piece - 1) / piece);
    _Atomic int failed = 0;
    range[0] = INFINITY;
    range[1] = -INFINITY;
#pragma omp parallel if (n > 1)
    {
        double mine[2] = {INFINITY, -INFINITY};
#pragma omp for schedule(static)
        for (int64_t i = 0; i < n; i++) {
            const size_t off = (size_t)i * piece, len = bytes - off < piece ? bytes - off : piece;
            int e = atomic_load(&failed) ? -1 : take(ctx, p + off, off, len);
            if (e > 0) {
                int none = 0;
                atomic_compare_exchange_strong(&failed, &none, e);
            } else if (e == 0)
                vv_range_accumulate(type, p + off, len / es, mine);
        }
#pragma omp critical(sbx_volume_range)
        {
            range[0] = mine[0] < range[0] ? mine[0] : range[0];
            range[1] = mine[1] > range[1] ? mine[1] : range[1];
        }
    }
    return atomic_load(&failed);
}

/* take_and_range's take of a mapping of the reader's memfd: the piece's
 * pages populated (MADV_POPULATE_READ; refused before Linux 5.14: then
 * faulted as they are read). */
static int
populate_piece(void *ctx, unsigned char *at, size_t off, size_t len) {
    (void)ctx;
    (void)off;
    (void)madvise(at, len, MADV_POPULATE_READ);
    return 0;
}

/* ---- the reader ----------------------------------------------------------------- */

/* The voxels of the volumes the reader makes: each in its own memfd. */
typedef struct sbx_block {
    void *data;
    size_t bytes;
    int fd;
} sbx_block;
static sbx_block blocks[8];
static pthread_mutex_t blocks_lock = PTHREAD_MUTEX_INITIALIZER;

void *
sbx_memfd_alloc(size_t bytes) {
    size_t len = bytes ? bytes : 1;
    int fd = memfd_create("volvis-voxels", MFD_CLOEXEC | MFD_ALLOW_SEALING);
    if (fd < 0)
        return NULL;
    void *p = MAP_FAILED;
    if (ftruncate(fd, (off_t)len) == 0)
        p = mmap(NULL, len, PROT_READ | PROT_WRITE, MAP_SHARED, fd, 0);
    if (p == MAP_FAILED) {
        close(fd);
        return NULL;
    }
    /* the pages made ahead, in parallel (a fault a page costs more) */
    sbx_madvise_parallel(p, len, MADV_POPULATE_WRITE);
    pthread_mutex_lock(&blocks_lock);
    int slot = -1;
    for (int i = 0; i < (int)(sizeof blocks / sizeof blocks[0]) && slot < 0; i++)
        if (!blocks[i].data)
            slot = i;
    if (slot >= 0)
        blocks[slot] = (sbx_block){p, len, fd};
    pthread_mutex_unlock(&blocks_lock);
    if (slot < 0) {
        munmap(p, len);
        close(fd);
        return NULL;
    }
    return p;
}

void
sbx_memfd_release(void *user, void *data) {
    (void)user;
    pthread_mutex_lock(&blocks_lock);
    for (int i = 0; i < (int)(sizeof blocks / sizeof blocks[0]); i++)
        if (blocks[i].data == data) {
            munmap(data, blocks[i].bytes);
            close(blocks[i].fd);
            blocks[i] = (sbx_block){0};
        }
    pthread_mutex_unlock(&blocks_lock);
}

/* The memfd holding @p data; a copy into a new one when a reader made the
 * voxels some other way. -1 on failure. */
int
sbx_memfd_of(void *data, size_t bytes) {
    for (int i = 0; i < (int)(sizeof blocks / sizeof blocks[0]); i++)
        if (blocks[i].data == data && blocks[i].bytes >= bytes)
            return blocks[i].fd;
    void *p = sbx_memfd_alloc(bytes);
    if (!p)
        return -1;
    memcpy(p, data, bytes);
    return sbx_memfd_of(p, bytes);
}

/* @p fd sealed for handing over (the parent maps it), or -1 when it is -1
 * or cannot be sealed (then closed): this process's mapping of it is
 * removed first, so that it can be sealed against writing too (a memfd
 * with a writable shared mapping cannot be); nothing can change its bytes
 * once the parent has it. The injected "scribble" keeps its mapping and
 * hands it over unsealed against writing, as a hostile reader would. */
int
sbx_sealed(int fd, int scribble) {
    if (fd < 0)
        return -1;
    unsigned seals = F_SEAL_SHRINK | F_SEAL_GROW | F_SEAL_WRITE | F_SEAL_SEAL;
    if (scribble) {
        seals = F_SEAL_SHRINK | F_SEAL_GROW;
    } else {
        pthread_mutex_lock(&blocks_lock);
        for (int i = 0; i < (int)(sizeof blocks / sizeof blocks[0]); i++)
            if (blocks[i].fd == fd && blocks[i].data) {
                /* the page tables dropped in parallel first (the memfd
                 * keeps the pages), so that the unmap has nothing to do */
                sbx_madvise_parallel(blocks[i].data, blocks[i].bytes, MADV_DONTNEED);
                munmap(blocks[i].data, blocks[i].bytes);
                blocks[i].data = NULL; /* the fd stays open: it is handed over */
            }
        pthread_mutex_unlock(&blocks_lock);
    }
    if (fcntl(fd, F_ADD_SEALS, seals) != 0) {
        close(fd);
        return -1;
    }
    return fd;
}

int
sbx_mesh_memfd(const vv_mesh *m, uint64_t *bytes) {
    const size_t pos = m->n_vertices * 3 * sizeof(float),
                 tri = m->n_triangles * 3 * sizeof(uint32_t);
    *bytes = (uint64_t)(pos + tri);
    char *p = sbx_memfd_alloc(pos + tri);
    if (!p)
        return -1;
    memcpy(p, m->positions, pos);
    memcpy(p + pos, m->triangles, tri);
    return sbx_memfd_of(p, pos + tri);
}

int
sbx_grid_memfd(const vv_grid *g, uint64_t *out_bytes) {
    const int sph = g->kind == VV_GRID_SPHERICAL;
    const uint64_t n_conn = g->n_cells ? g->cell_offsets[g->n_cells] : 0;
    const uint64_t n_axes =
        sph ? (uint64_t)g->sph_dims[0] + (uint64_t)g->sph_dims[1] + (uint64_t)g->sph_dims[2] : 0;
    uint64_t bytes = sbx_pad8(sizeof(sbx_grid_head)) + sbx_pad8(g->n_points * 3 * sizeof(double)) +
                     sbx_pad8(g->n_cells) + sbx_pad8((g->n_cells + 1) * sizeof(uint64_t)) +
                     sbx_pad8(n_conn * sizeof(uint32_t)) +
                     sbx_pad8((uint64_t)g->n_blocks * 3 * sizeof(int32_t)) + n_axes * 8;
    for (int i = 0; i < g->n_fields; i++)
        bytes += sizeof(sbx_grid_field) +
                 sbx_pad8(g->fields[i].n_tuples * (uint64_t)g->fields[i].n_components * 4);
    char *p = sbx_memfd_alloc((size_t)bytes), *q = p;
    if (p) {
        sbx_grid_head h = {.kind = g->kind,
                           .n_fields = g->n_fields,
                           .n_blocks = g->n_blocks,
                           .n_points = g->n_points,
                           .n_cells = g->n_cells,
                           .n_conn = n_conn};
        if (sph)
            memcpy(h.sph_dims, g->sph_dims, sizeof h.sph_dims);
        memcpy(q, &h, sizeof h);
        q += sbx_pad8(sizeof h);
        memcpy(q, g->points, g->n_points * 3 * sizeof(double));
        q += sbx_pad8(g->n_points * 3 * sizeof(double));
        memcpy(q, g->cell_types, g->n_cells);
        q += sbx_pad8(g->n_cells);
        for (size_t c = 0; c <= g->n_cells; c++) {
            uint64_t o = g->n_cells ? g->cell_offsets[c] : 0;
            memcpy(q + 8 * c, &o, 8);
        }
        q += sbx_pad8((g->n_cells + 1) * sizeof(uint64_t));
        memcpy(q, g->connectivity, n_conn * sizeof(uint32_t));
        q += sbx_pad8(n_conn * sizeof(uint32_t));
        for (int b = 0; b < g->n_blocks; b++)
            for (int a = 0; a < 3; a++) {
                int32_t d = g->block_dims[b][a];
                memcpy(q + 4 * (3 * b + a), &d, 4);
            }
        q += sbx_pad8((uint64_t)g->n_blocks * 3 * sizeof(int32_t));
        for (int a = 0; a < 3 && sph; a++) {
            memcpy(q, g->sph_axes[a], (size_t)g->sph_dims[a] * sizeof(double));
            q += (size_t)g->sph_dims[a] * sizeof(double);
        }
        for (int i = 0; i < g->n_fields; i++) {
            const vv_grid_field *f = &g->fields[i];
            sbx_grid_field fh = {.cell_data = f->cell_data,
                                 .n_components = f->n_components,
                                 .has_fill = f->has_fill,
                                 .fill = f->fill,
                                 .n_tuples = f->n_tuples};
            memcpy(fh.name, f->name, sizeof fh.name);
            memcpy(q, &fh, sizeof fh);
            q += sizeof fh;
            memcpy(q, f->values, f->n_tuples * (size_t)f->n_components * sizeof(float));
            q += sbx_pad8(f->n_tuples * (uint64_t)f->n_components * 4);
        }
    }
    *out_bytes = bytes;
    return p ? sbx_memfd_of(p, (size_t)bytes) : -1;
}

/* ---- the parent ----------------------------------------------------------------- */

static void
release_mapping(void *user, void *data) {
    munmap(data, (size_t)(uintptr_t)user);
}

static int
finite_all(const double *x, int n) {
    for (int i = 0; i < n; i++)
        if (!isfinite(x[i]))
            return 0;
    return 1;
}

/* The reply's geometry and provenance into @p v (enumerations out of range
 * taken as unknown; the geometry was checked finite). */
static void
take_geometry(vv_volume *v, const sbx_reply *r) {
    memcpy(v->spacing, r->spacing, sizeof v->spacing);
    memcpy(v->origin, r->origin, sizeof v->origin);
    memcpy(v->direction, r->direction, sizeof v->direction);
    v->unit = r->unit >= 0 && r->unit <= VV_UNIT_LAST ? (vv_unit)r->unit : VV_UNIT_UNKNOWN;
    v->data_origin = r->data_origin >= 0 && r->data_origin <= VV_ORIGIN_OTHER
                         ? (vv_data_origin)r->data_origin
                         : VV_ORIGIN_OTHER;
    v->modification = r->modification >= 0 && r->modification <= VV_MOD_OTHER
                          ? (vv_modification)r->modification
                          : VV_MOD_OTHER;
    v->space = r->space == VV_SPACE_RAS || r->space == VV_SPACE_LPS ? (vv_space)r->space
                                                                    : VV_SPACE_UNKNOWN;
}

/* The volume of a result reply and its memfd: sizes against the memfd,
 * its seals, a finite geometry. Owns @p fd. */
vv_status
sbx_volume_from_reply(vv_volume **out, const sbx_reply *r, int fd, const char *fmt_name,
                      const char *file) {
    uint64_t bytes = 0;
    vv_status s = VV_OK;
    struct stat st;
    int seals = fd >= 0 ? fcntl(fd, F_GET_SEALS) : -1;
    if (fd < 0 || r->type < VV_U8 || r->type > VV_F64)
        s = vv_error_set(VV_ERR_FORMAT, "%s: %s: the reader's result has no voxels", fmt_name,
                         file);
    else if ((s = vv_volume_check_size(r->dims, (vv_voxel_type)r->type, &bytes)) != VV_OK)
        s = vv_error_prefix(s, "%s: %s: the reader's result", fmt_name, file);
    else if (bytes != r->bytes || fstat(fd, &st) != 0 || (uint64_t)st.st_size < bytes ||
             seals < 0 || !(seals & F_SEAL_SHRINK))
        s = vv_error_set(VV_ERR_FORMAT,
                         "%s: %s: the reader's result does not hold the %llu bytes it names",
                         fmt_name, file, (unsigned long long)bytes);
    else if (!(seals & F_SEAL_WRITE))
        s = vv_error_set(VV_ERR_FORMAT,
                         "%s: %s: the reader's voxels are not sealed against writing; the file is "
                         "hostile or the reader broken",
                         fmt_name, file);
    else if (!finite_all(r->spacing, 3) || !finite_all(r->origin, 3) ||
             !finite_all(r->direction, 9) || !(r->spacing[0] > 0) || !(r->spacing[1] > 0) ||
             !(r->spacing[2] > 0))
        s = vv_error_set(VV_ERR_FORMAT, "%s: %s: the reader's result has a broken geometry",
                         fmt_name, file);
    if (s != VV_OK) {
        if (fd >= 0)
            close(fd);
        return s;
    }
    /* private: the memfd is sealed against writing; the page cache's pages
     * are mapped read-only (populated without copying) and copied only
     * where the program writes to the volume */
    size_t len = bytes ? (size_t)bytes : 1;
    void *p = mmap(NULL, len, PROT_READ | PROT_WRITE, MAP_PRIVATE, fd, 0);
    int e = errno;
    close(fd);
    double range[2] = {0, 0};
    if (p != MAP_FAILED && bytes)
        (void)take_and_range(p, (size_t)bytes, (size_t)8 << 20, (vv_voxel_type)r->type,
                             populate_piece, NULL, range);
    if (p == MAP_FAILED)
        return vv_error_set(VV_ERR_NOMEM, "%s: %s: cannot map the reader's %llu bytes: %s",
                            fmt_name, file, (unsigned long long)bytes, strerror(e));
    vv_volume *v = NULL;
    s = vv_volume_wrap(&v, r->dims, (vv_voxel_type)r->type, p, release_mapping,
                       (void *)(uintptr_t)len);
    if (s != VV_OK) {
        munmap(p, len);
        return s;
    }
    vv_volume_set_range(v, range);
    take_geometry(v, r);
    *out = v;
    return VV_OK;
}

/* take_and_range's take of a piece of a peek reply's voxels: copied out
 * of the reader (process_vm_readv, which may copy less than asked at a
 * time). */
typedef struct peer_copy {
    pid_t peer;
    uint64_t addr;
} peer_copy;

static int
copy_piece(void *ctx, unsigned char *at, size_t off, size_t len) {
    const peer_copy *c = ctx;
    for (size_t got = 0; got < len;) {
        struct iovec here = {at + got, len - got};
        struct iovec there = {(void *)(uintptr_t)(c->addr + off + got), len - got};
        const ssize_t k = process_vm_readv(c->peer, &here, 1, &there, 1, 0);
        if (k < 0 && errno == EINTR)
            continue;
        if (k <= 0)
            return k < 0 && errno ? errno : EFAULT;
        got += (size_t)k;
    }
    return 0;
}

vv_status
sbx_volume_from_peer(vv_volume **out, const sbx_reply *r, pid_t peer, const char *fmt_name,
                     const char *file) {
    uint64_t bytes = 0;
    vv_status s = VV_OK;
    if (peer <= 0 || !r->addr || r->type < VV_U8 || r->type > VV_F64)
        return vv_error_set(VV_ERR_FORMAT, "%s: %s: the reader's result has no voxels", fmt_name,
                            file);
    if ((s = vv_volume_check_size(r->dims, (vv_voxel_type)r->type, &bytes)) != VV_OK)
        return vv_error_prefix(s, "%s: %s: the reader's result", fmt_name, file);
    if (bytes == 0 || bytes != r->bytes || r->addr > UINTPTR_MAX - bytes)
        return vv_error_set(VV_ERR_FORMAT,
                            "%s: %s: the reader's result does not hold the %llu bytes it names",
                            fmt_name, file, (unsigned long long)bytes);
    if (!finite_all(r->spacing, 3) || !finite_all(r->origin, 3) || !finite_all(r->direction, 9) ||
        !(r->spacing[0] > 0) || !(r->spacing[1] > 0) || !(r->spacing[2] > 0))
        return vv_error_set(VV_ERR_FORMAT, "%s: %s: the reader's result has a broken geometry",
                            fmt_name, file);
    vv_volume *v = NULL;
    if ((s = vv_volume_new(&v, r->dims, (vv_voxel_type)r->type)) != VV_OK)
        return s;
    double range[2];
    peer_copy pc = {peer, r->addr};
    const int e =
        take_and_range(v->data, (size_t)bytes, (size_t)4 << 20, v->type, copy_piece, &pc, range);
    if (e) {
        vv_volume_free(v);
        return vv_error_set(VV_ERR_FORMAT,
                            "%s: %s: cannot copy the reader's %llu bytes of voxels: %s; the file "
                            "is hostile or the reader broken",
                            fmt_name, file, (unsigned long long)bytes, strerror(e));
    }
    vv_volume_set_range(v, range);
    take_geometry(v, r);
    *out = v;
    return VV_OK;
}

vv_status
sbx_blob_from_reply(void **out, size_t *len, const sbx_reply *r, int fd, const char *name,
                    const char *file) {
    struct stat st;
    int seals = fd >= 0 ? fcntl(fd, F_GET_SEALS) : -1;
    void *a = NULL;
    vv_status s = VV_OK;
    if (fd < 0 || r->bytes == 0 || r->bytes > SBX_MAX_LIST_BYTES || fstat(fd, &st) != 0 ||
        (uint64_t)st.st_size < r->bytes || seals < 0 || !(seals & F_SEAL_SHRINK))
        s = vv_error_set(VV_ERR_FORMAT, "%s: %s: the reader's listing is malformed", name, file);
    else if (!(a = malloc((size_t)r->bytes)))
        s = vv_error_set(VV_ERR_NOMEM, "out of memory");
    /* copied: it is small, and the reader could still write to its memfd */
    for (size_t got = 0; s == VV_OK && got < r->bytes;) {
        ssize_t k = pread(fd, (char *)a + got, (size_t)r->bytes - got, (off_t)got);
        if (k < 0 && errno == EINTR)
            continue;
        if (k <= 0)
            s = vv_error_set(VV_ERR_IO, "%s: %s: cannot read the reader's listing", name, file);
        else
            got += (size_t)k;
    }
    if (fd >= 0)
        close(fd);
    if (s != VV_OK) {
        free(a);
        return s;
    }
    *out = a;
    *len = (size_t)r->bytes;
    return VV_OK;
}

/* The mesh of a result reply and its memfd (copied into a new mesh, every
 * index checked; normals computed here). Owns @p fd. */
vv_status
sbx_mesh_from_reply(vv_mesh **out, const sbx_reply *r, int fd, const char *name, const char *file) {
    struct stat st;
    int seals = fd >= 0 ? fcntl(fd, F_GET_SEALS) : -1;
    const uint64_t nv = r->n_vertices, nt = r->n_triangles;
    vv_status s = VV_OK;
    if (fd < 0 || nv < 3 || nt < 1 || nv > VV_MESH_MAX_ELEMENTS || nt > VV_MESH_MAX_ELEMENTS ||
        r->bytes != nv * 3 * sizeof(float) + nt * 3 * sizeof(uint32_t) || fstat(fd, &st) != 0 ||
        (uint64_t)st.st_size < r->bytes || seals < 0 || !(seals & F_SEAL_SHRINK)) {
        if (fd >= 0)
            close(fd);
        return vv_error_set(VV_ERR_FORMAT, "%s: %s: the reader's mesh is malformed", name, file);
    }
    void *p = mmap(NULL, (size_t)r->bytes, PROT_READ, MAP_SHARED, fd, 0);
    int e = errno;
    close(fd);
    if (p == MAP_FAILED)
        return vv_error_set(VV_ERR_NOMEM, "%s: %s: cannot map the reader's %llu bytes: %s", name,
                            file, (unsigned long long)r->bytes, strerror(e));
    const float *pos = p;
    const uint32_t *tri = (const uint32_t *)((const char *)p + nv * 3 * sizeof(float));
    vv_mesh *m = NULL;
    if ((s = vv_mesh_new(&m)) == VV_OK &&
        (s = vv_mesh_reserve(m, (size_t)nv, (size_t)nt)) == VV_OK) {
        memcpy(m->positions, pos, (size_t)nv * 3 * sizeof(float));
        m->n_vertices = (size_t)nv;
        for (uint64_t i = 0; i < 3 * nv && s == VV_OK; i++)
            if (!isfinite(m->positions[i]))
                s = vv_error_set(VV_ERR_FORMAT, "vertex %llu is not finite",
                                 (unsigned long long)(i / 3));
        for (uint64_t t = 0; t < nt && s == VV_OK; t++) /* checks every index */
            s = vv_mesh_add_triangle(m, tri[3 * t], tri[3 * t + 1], tri[3 * t + 2]);
        if (s == VV_OK)
            s = vv_mesh_compute_normals(m);
    }
    munmap(p, (size_t)r->bytes);
    if (s != VV_OK) {
        vv_mesh_free(m);
        return vv_error_prefix(s, "%s: %s: the reader's result", name, file);
    }
    *out = m;
    return VV_OK;
}

/* A cursor over a grid's memfd: take() hands out the next section of @p n
 * bytes (rounded up to 8), or NULL past the end. */
typedef struct grid_cursor {
    const char *p;
    uint64_t at, size;
} grid_cursor;

static const void *
take(grid_cursor *c, uint64_t n) {
    if (sbx_pad8(n) > c->size - c->at) /* n is bounded by the grid limits: no overflow */
        return NULL;
    const void *q = c->p + c->at;
    c->at += sbx_pad8(n);
    return q;
}

/* Copies the grid of a mapped memfd into @p g, checking what it copied. */
static vv_status
grid_copy(vv_grid *g, grid_cursor *c) {
    sbx_grid_head h;
    const void *q = take(c, sizeof h);
    if (!q)
        return vv_error_set(VV_ERR_FORMAT, "grid: no grid head");
    memcpy(&h, q, sizeof h);
    if (h.kind < VV_GRID_UNSTRUCTURED || h.kind > VV_GRID_SPHERICAL || h.n_fields < 0 ||
        h.n_fields > VV_GRID_MAX_FIELDS || h.n_blocks < 0 || h.n_blocks > VV_GRID_MAX_BLOCKS ||
        (h.kind == VV_GRID_CURVILINEAR) != (h.n_blocks > 0))
        return vv_error_set(VV_ERR_FORMAT, "grid: a grid head out of range");
    vv_status s = vv_grid_alloc(g, (size_t)h.n_points, (size_t)h.n_cells, (size_t)h.n_conn);
    if (s != VV_OK)
        return s;
    g->kind = (vv_grid_kind)h.kind;
    const uint64_t np = h.n_points, nc = h.n_cells, nk = h.n_conn;
    if (!(q = take(c, np * 3 * sizeof(double))))
        return vv_error_set(VV_ERR_FORMAT, "grid: %llu points past its end",
                            (unsigned long long)np);
    memcpy(g->points, q, (size_t)np * 3 * sizeof(double));
    for (uint64_t i = 0; i < 3 * np; i++)
        if (!isfinite(g->points[i]))
            return vv_error_set(VV_ERR_FORMAT, "grid: point %llu is not finite",
                                (unsigned long long)(i / 3));
    if (!(q = take(c, nc)))
        return vv_error_set(VV_ERR_FORMAT, "grid: %llu cells past its end", (unsigned long long)nc);
    memcpy(g->cell_types, q, (size_t)nc);
    if (!(q = take(c, (nc + 1) * sizeof(uint64_t))))
        return vv_error_set(VV_ERR_FORMAT, "grid: cell offsets past its end");
    for (uint64_t i = 0; i <= nc; i++) {
        uint64_t o;
        memcpy(&o, (const char *)q + 8 * i, 8);
        if (o > nk)
            return vv_error_set(VV_ERR_FORMAT,
                                "grid: cell offset %llu is past the %llu point indices",
                                (unsigned long long)i, (unsigned long long)nk);
        g->cell_offsets[i] = (size_t)o;
    }
    if (nc && g->cell_offsets[nc] != nk)
        return vv_error_set(VV_ERR_FORMAT, "grid: the cells use %zu of %llu point indices",
                            g->cell_offsets[nc], (unsigned long long)nk);
    if (!(q = take(c, nk * sizeof(uint32_t))))
        return vv_error_set(VV_ERR_FORMAT, "grid: point indices past its end");
    memcpy(g->connectivity, q, (size_t)nk * sizeof(uint32_t));
    if (h.n_blocks) {
        if (!(q = take(c, (uint64_t)h.n_blocks * 3 * sizeof(int32_t))) ||
            !(g->block_dims = malloc((size_t)h.n_blocks * sizeof *g->block_dims)))
            return vv_error_set(q ? VV_ERR_NOMEM : VV_ERR_FORMAT, "grid: no room for %d blocks",
                                h.n_blocks);
        memcpy(g->block_dims, q, (size_t)h.n_blocks * sizeof *g->block_dims);
        g->n_blocks = h.n_blocks;
        uint64_t sum = 0;
        for (int b = 0; b < h.n_blocks; b++) {
            uint64_t k = 1;
            for (int a = 0; a < 3; a++) {
                const int d = g->block_dims[b][a];
                if (d < 2 || d > (int)VV_GRID_MAX_POINTS)
                    return vv_error_set(VV_ERR_FORMAT, "grid: block %d has a dimension of %d", b,
                                        d);
                k *= (uint64_t)d;
            }
            if ((sum += k) > np)
                break;
        }
        if (sum != np)
            return vv_error_set(VV_ERR_FORMAT, "grid: its blocks do not hold its %llu points",
                                (unsigned long long)np);
    }
    if (h.kind == VV_GRID_SPHERICAL) {
        uint64_t k = 1;
        for (int a = 0; a < 3; a++) {
            const int d = h.sph_dims[a];
            if (d < 2 || (uint64_t)d > np || (k *= (uint64_t)d) > np) {
                k = UINT64_MAX; /* never np */
                break;
            }
        }
        if (k != np)
            return vv_error_set(
                VV_ERR_FORMAT, "grid: spherical axes of %d x %d x %d values for %llu points",
                h.sph_dims[0], h.sph_dims[1], h.sph_dims[2], (unsigned long long)np);
        for (int a = 0; a < 3; a++) {
            const size_t d = (size_t)h.sph_dims[a];
            if (!(q = take(c, d * sizeof(double))) ||
                !(g->sph_axes[a] = malloc(d * sizeof(double))))
                return vv_error_set(q ? VV_ERR_NOMEM : VV_ERR_FORMAT, "grid: no room for an axis");
            memcpy(g->sph_axes[a], q, d * sizeof(double));
            g->sph_dims[a] = (int)d;
            for (size_t i = 0; i < d; i++)
                if (!isfinite(g->sph_axes[a][i]) ||
                    (i && !(g->sph_axes[a][i] > g->sph_axes[a][i - 1])))
                    return vv_error_set(VV_ERR_FORMAT, "grid: a spherical axis not increasing");
        }
    }
    for (int i = 0; i < h.n_fields; i++) {
        sbx_grid_field fh;
        if (!(q = take(c, sizeof fh)))
            return vv_error_set(VV_ERR_FORMAT, "grid: field %d past its end", i);
        memcpy(&fh, q, sizeof fh);
        fh.name[sizeof fh.name - 1] = '\0';
        for (char *ch = fh.name; *ch; ch++) /* printable, for messages and lists */
            if ((unsigned char)*ch < 0x20 || *ch == 0x7f)
                *ch = '?';
        vv_grid_field *f = NULL;
        if ((s = vv_grid_add_field(g, fh.name, fh.cell_data != 0, fh.n_components, &f)) != VV_OK)
            return s;
        if (fh.n_tuples != f->n_tuples)
            return vv_error_set(VV_ERR_FORMAT, "grid: field '%s' has %llu tuples for %zu", f->name,
                                (unsigned long long)fh.n_tuples, f->n_tuples);
        const uint64_t vb = (uint64_t)f->n_tuples * (uint64_t)f->n_components * sizeof(float);
        if (!(q = take(c, vb)))
            return vv_error_set(VV_ERR_FORMAT, "grid: field '%s' past its end", f->name);
        memcpy(f->values, q, (size_t)vb);
        f->has_fill = fh.has_fill != 0;
        f->fill = fh.fill;
        vv_grid_field_update_range(f);
    }
    return vv_grid_validate(g);
}

/* The grid of a result reply and its memfd (copied into a new grid, then
 * checked). Owns @p fd. */
vv_status
sbx_grid_from_reply(vv_grid **out, const sbx_reply *r, int fd, const char *fmt_name,
                    const char *file) {
    struct stat st;
    int seals = fd >= 0 ? fcntl(fd, F_GET_SEALS) : -1;
    if (fd < 0 || r->bytes < sizeof(sbx_grid_head) || r->bytes > ((uint64_t)1 << 46) ||
        fstat(fd, &st) != 0 || (uint64_t)st.st_size < r->bytes || seals < 0 ||
        !(seals & F_SEAL_SHRINK)) {
        if (fd >= 0)
            close(fd);
        return vv_error_set(VV_ERR_FORMAT, "%s: %s: the reader's grid is malformed", fmt_name,
                            file);
    }
    void *p = mmap(NULL, (size_t)r->bytes, PROT_READ, MAP_SHARED, fd, 0);
    int e = errno;
    close(fd);
    if (p == MAP_FAILED)
        return vv_error_set(VV_ERR_NOMEM, "%s: %s: cannot map the reader's %llu bytes: %s",
                            fmt_name, file, (unsigned long long)r->bytes, strerror(e));
    grid_cursor c = {p, 0, r->bytes};
    vv_grid *g = NULL;
    vv_status s = vv_grid_new(&g, VV_GRID_UNSTRUCTURED);
    if (s == VV_OK)
        s = grid_copy(g, &c);
    munmap(p, (size_t)r->bytes);
    if (s != VV_OK) {
        vv_grid_free(g);
        return vv_error_prefix(s, "%s: %s: the reader's", fmt_name, file);
    }
    *out = g;
    return VV_OK;
}

int
sbx_take_message(int op, const void *msg, size_t len, int fd, char name[VV_SANDBOX_NAME_MAX],
                 char title[64], const char *file, vv_sandbox_result *out, vv_status *status) {
    return sbx_take_message_peer(op, msg, len, fd, 0, name, title, file, out, status);
}

int
sbx_take_message_peer(int op, const void *msg, size_t len, int fd, pid_t peer,
                      char name[VV_SANDBOX_NAME_MAX], char title[64], const char *file,
                      vv_sandbox_result *out, vv_status *status) {
    memset(out, 0, sizeof *out);
    sbx_reply *r = malloc(sizeof *r);
    if (!r) {
        if (fd >= 0)
            close(fd);
        *status = vv_error_set(VV_ERR_NOMEM, "out of memory");
        return 1;
    }
    int whole = len >= offsetof(sbx_reply, err) && len <= sizeof *r;
    if (whole) {
        memcpy(r, msg, len);
        whole = r->magic == SBX_MAGIC && r->err_len < SBX_MAX_ERROR &&
                len == offsetof(sbx_reply, err) + r->err_len &&
                (r->kind == SBX_FORMAT || r->kind == SBX_RESULT) &&
                r->info_len <= VV_SANDBOX_INFO_MAX;
    }
    if (!whole || r->kind == SBX_FORMAT) {
        if (fd >= 0)
            close(fd);
        /* the row the reader names: a printable name and title */
        if (whole && memchr(r->format, 0, sizeof r->format) &&
            memchr(r->title, 0, sizeof r->title) && r->format[0]) {
            sbx_printable(r->format, sizeof r->format);
            sbx_printable(r->title, sizeof r->title);
            snprintf(name, VV_SANDBOX_NAME_MAX, "%s", r->format);
            snprintf(title, 64, "%s", r->title);
        }
        free(r);
        return whole ? 0 : -1;
    }
    r->err[r->err_len] = '\0';
    sbx_printable(r->err, sizeof r->err);
    if (r->status != VV_OK) {
        if (fd >= 0)
            close(fd);
        vv_status e =
            r->status >= VV_ERR_CANCELLED && r->status < 0 ? (vv_status)r->status : VV_ERR_FORMAT;
        *status = r->err[0]
                      ? vv_error_set(e, "%s", r->err)
                      : vv_error_set(e, "%s: %s: the reader failed without a message", name, file);
    } else if (op == VV_SANDBOX_LIST) {
        *status = sbx_blob_from_reply(&out->blob, &out->blob_len, r, fd, name, file);
    } else if (op == VV_SANDBOX_MESH) {
        *status = sbx_mesh_from_reply(&out->mesh, r, fd, name, file);
    } else if (op == VV_SANDBOX_GRID) {
        *status = sbx_grid_from_reply(&out->grid, r, fd, name, file);
    } else if (fd < 0 && peer > 0 && r->addr) { /* asked with peek: copied out of the reader */
        *status = sbx_volume_from_peer(&out->volume, r, peer, name, file);
    } else {
        *status = sbx_volume_from_reply(&out->volume, r, fd, name, file);
    }
    if (*status == VV_OK) {
        memcpy(out->info, r->info, r->info_len);
        out->info_len = r->info_len;
        snprintf(out->format, sizeof out->format, "%s", name);
    }
    free(r);
    return 1;
}

/* The bytes of a store's window: its table, or its largest chunk. 0 when
 * a chunk is over SBX_MAX_BOX_BYTES. */
uint64_t
sbx_window_bytes(const sbx_store_head *h) {
    uint64_t w = sizeof *h;
    for (int l = 0; l < h->n_levels; l++) {
        uint64_t c = vv_voxel_type_size((vv_voxel_type)h->lv[l].type);
        for (int k = 0; k < 3; k++)
            c *= (uint64_t)(h->lv[l].cdims[k] < h->lv[l].dims[k] ? h->lv[l].cdims[k]
                                                                 : h->lv[l].dims[k]);
        if (c > SBX_MAX_BOX_BYTES)
            return 0;
        w = c > w ? c : w;
    }
    return w;
}

uint32_t
sbx_layout(void) {
    const uint64_t sizes[] = {sizeof(sbx_request), sizeof(sbx_reply), sizeof(sbx_store_head),
                              sizeof(sbx_box), VV_SANDBOX_INFO_MAX};
    uint32_t h = 2166136261u; /* FNV-1a over the sizes' bytes */
    for (size_t i = 0; i < sizeof sizes / sizeof sizes[0]; i++)
        for (int b = 0; b < 8; b++) {
            h ^= (uint32_t)((sizes[i] >> (8 * b)) & 0xff);
            h *= 16777619u;
        }
    return h ? h : 1; /* 0 is a reader from before the fingerprint */
}

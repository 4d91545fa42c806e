/*
 * libFuzzer harness: the parent's side of the reader sandbox
 * (sbx_take_message; src/sandbox/payload.c). Whatever a broken or hostile
 * volvis-reader sends (any message, a memfd of any size and seals, or none),
 * the parent must not crash, leak or hang: it makes a volume that holds all
 * its voxels, an error of one line, or "malformed".
 *
 * The input: a flags byte, a message length (two bytes, little-endian),
 * the message, then what the memfd holds. Flags: 1 a memfd is passed; 2 it
 * is sealed against shrinking, 4 against growing and writing; 8 the message is made
 * plausible (the magic, a kind, err_len fitting the length, and with 16 the
 * byte count naming the memfd's size), so the fuzzer spends its time past
 * the first checks; 32 a second message follows the format message;
 * 64 and 128 pick the answer asked for: a volume, a listing's bytes (the
 * caller checks them: a DICOM folder's series, io/transport.c), a mesh
 * (with 8, a mesh's counts are made to fill the memfd) or a grid (the
 * memfd's sections as sbx_grid_head lays them out).
 */
#define _GNU_SOURCE
#include <fcntl.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <unistd.h>

#include "fuzz_util.h"
#include "io/transport.h"
#include "sandbox/sandbox_internal.h"
#include "volvis/volvis.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static int
make_memfd(const uint8_t *d, size_t n, int flags) {
    int fd = memfd_create("fuzz-voxels", MFD_CLOEXEC | MFD_ALLOW_SEALING);
    if (fd < 0)
        __builtin_trap(); /* the machine, not the input */
    size_t off = 0;
    while (off < n) {
        ssize_t w = write(fd, d + off, n - off);
        if (w <= 0)
            __builtin_trap();
        off += (size_t)w;
    }
    int seals = (flags & 2 ? F_SEAL_SHRINK : 0) | (flags & 4 ? F_SEAL_GROW | F_SEAL_WRITE : 0);
    if (seals)
        fcntl(fd, F_ADD_SEALS, seals);
    return fd;
}

int
LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    if (size < 3)
        return 0;
    const int flags = data[0];
    size_t len = (size_t)data[1] | (size_t)data[2] << 8;
    data += 3;
    size -= 3;
    if (len > size)
        len = size;
    static sbx_reply msg;
    if (len > sizeof msg)
        len = sizeof msg;
    memset(&msg, 0, sizeof msg);
    memcpy(&msg, data, len);
    const uint8_t *rest = data + len;
    const size_t nrest = size - len;
    if (flags & 8) {
        msg.magic = SBX_MAGIC;
        msg.kind = flags & 32 ? SBX_FORMAT : SBX_RESULT;
        if (len < offsetof(sbx_reply, err))
            len = offsetof(sbx_reply, err);
        msg.err_len = (uint32_t)(len - offsetof(sbx_reply, err));
        if (flags & 16)
            msg.bytes = nrest;
    }
    const int ops[4] = {VV_SANDBOX_VOLUME, VV_SANDBOX_LIST, VV_SANDBOX_MESH, VV_SANDBOX_GRID};
    const int op = ops[(flags >> 6) & 3];
    if ((flags & 8) && op == VV_SANDBOX_MESH && msg.n_vertices < 1024) {
        msg.n_triangles = nrest > 36 ? (nrest - 36) / 12 : 1;
        msg.n_vertices = 3;
    }
    char name[VV_SANDBOX_NAME_MAX] = "nrrd", title[64] = "NRRD";
    vv_sandbox_result a;
    memset(&a, 0, sizeof a);
    vv_status st = VV_OK;
    int fd = flags & 1 ? make_memfd(rest, nrest, flags) : -1;
    int k = sbx_take_message(op, &msg, len, fd, name, title, "in.nrrd", &a, &st);
    if (k == 0 && (flags & 32)) {
        /* the result after the format message: the same bytes as a result */
        msg.kind = SBX_RESULT;
        fd = flags & 1 ? make_memfd(rest, nrest, flags) : -1;
        k = sbx_take_message(op, &msg, len, fd, name, title, "in.nrrd", &a, &st);
    }
    if (strnlen(name, sizeof name) == sizeof name || strpbrk(name, "\n\r\x1b") ||
        strnlen(title, sizeof title) == sizeof title || strpbrk(title, "\n\r\x1b"))
        __builtin_trap(); /* the reader's names: one line, ended */
    const int got = a.volume || a.blob || a.mesh || a.grid;
    if (k <= 0 || st != VV_OK) {
        if (got)
            __builtin_trap(); /* a result with an error or without a result */
        if (k > 0 && strpbrk(vv_error_message(), "\n\r\x1b"))
            __builtin_trap(); /* the error is one line of text */
        return 0;
    }
    if (op == VV_SANDBOX_VOLUME) {
        fuzz_check_volume(a.volume);
    } else if (op == VV_SANDBOX_LIST) {
        if (!a.blob || a.blob_len != msg.bytes)
            __builtin_trap(); /* the listing's bytes, all of them */
        volatile unsigned char last = ((unsigned char *)a.blob)[a.blob_len - 1];
        (void)last;
        /* as a DICOM folder's series: checked or refused in one line */
        vv_dicom_series *series = NULL;
        int n = 0;
        if (io_dicom_series_from_wire(&series, &n, a.blob, a.blob_len, "in") == VV_OK) {
            if (!series || n < 1)
                __builtin_trap();
            for (int i = 0; i < n; i++) /* every string ends in its field */
                if (strnlen(series[i].first_file, sizeof series[i].first_file) ==
                        sizeof series[i].first_file ||
                    strnlen(series[i].patient_id, sizeof series[i].patient_id) ==
                        sizeof series[i].patient_id)
                    __builtin_trap();
            free(series);
        } else if (strpbrk(vv_error_message(), "\n\r\x1b")) {
            __builtin_trap();
        }
    } else if (op == VV_SANDBOX_GRID) {
        vv_grid *g = a.grid;
        if (!g || vv_grid_validate(g) != VV_OK)
            __builtin_trap();
        for (int i = 0; i < g->n_fields; i++) { /* every field holds its values */
            const vv_grid_field *f = &g->fields[i];
            const size_t n = f->n_tuples * (size_t)f->n_components;
            if (n) {
                volatile float last = f->values[n - 1]; /* ASan: inside the buffer */
                (void)last;
            }
        }
        vv_grid_free(g);
    } else {
        vv_mesh *m = a.mesh;
        if (!m || !m->normals)
            __builtin_trap();
        for (size_t t = 0; t < 3 * m->n_triangles; t++) /* every index names a vertex */
            if (m->triangles[t] >= m->n_vertices)
                __builtin_trap();
        vv_mesh_free(m);
    }
    return 0;
}

/* Shared helpers of the libFuzzer harnesses: see fuzz_util.h. */
#include "fuzz_util.h"

#include <dirent.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "volvis/volvis.h"

static char tmpdir[256];

static void
cleanup(void) {
    if (!tmpdir[0])
        return;
    DIR *d = opendir(tmpdir);
    if (d) {
        struct dirent *e;
        char p[512];
        while ((e = readdir(d)) != NULL) {
            if (!strcmp(e->d_name, ".") || !strcmp(e->d_name, ".."))
                continue;
            snprintf(p, sizeof p, "%s/%s", tmpdir, e->d_name);
            unlink(p);
        }
        closedir(d);
    }
    rmdir(tmpdir);
}

void
fuzz_init(void) {
    if (tmpdir[0])
        return;
    vv_memory_budget_set(FUZZ_MEMORY_BUDGET);
    vv_threads_set(1);
    /* our own parsers and checks are fuzzed, in this process; no harness
     * calls a sandboxed library (a reader process per input would run a
     * few dozen a second): fuzz_sandbox fuzzes the sandbox's parent side */
    setenv("VOLVIS_SANDBOX", "0", 0);
    /* the inputs are files: in memory (/dev/shm) unless TMPDIR says
     * otherwise, since a disk's writeback slowed the file-based harnesses
     * to a few hundred inputs a second */
    const char *base = getenv("TMPDIR");
    if (!base || !*base)
        base = access("/dev/shm", W_OK | X_OK) == 0 ? "/dev/shm" : "/tmp";
    snprintf(tmpdir, sizeof tmpdir, "%s/vvfuzz-XXXXXX", base);
    if (!mkdtemp(tmpdir)) {
        perror("fuzz: mkdtemp");
        abort();
    }
    atexit(cleanup);
}

const char *
fuzz_dir(void) {
    fuzz_init();
    return tmpdir;
}

const char *
fuzz_write(const char *name, const uint8_t *data, size_t size) {
    static char paths[8][512];
    static int slot;
    fuzz_init();
    char *p = paths[slot];
    slot = (slot + 1) % 8;
    snprintf(p, 512, "%s/%s", tmpdir, name);
    FILE *f = fopen(p, "wb");
    if (!f || (size && fwrite(data, 1, size, f) != size) || fclose(f) != 0) {
        perror("fuzz: writing the input");
        abort();
    }
    return p;
}

void
fuzz_split(const uint8_t *data, size_t size, const char *sep, const uint8_t **a, size_t *na,
           const uint8_t **b, size_t *nb) {
    size_t ls = strlen(sep);
    *a = data;
    *na = size;
    *b = data + size;
    *nb = 0;
    if (size < ls)
        return;
    for (size_t i = 0; i + ls <= size; i++) {
        if (memcmp(data + i, sep, ls) == 0) {
            *na = i;
            *b = data + i + ls;
            *nb = size - i - ls;
            return;
        }
    }
}

int
LLVMFuzzerInitialize(int *argc, char ***argv) {
    (void)argc;
    (void)argv;
    fuzz_init();
    return 0;
}

void
fuzz_check_volume(vv_volume *v) {
    if (!v)
        return;
    uint64_t n = vv_volume_voxel_count(v);
    if (n == 0 || !v->data)
        __builtin_trap();
    /* touch the first and last voxel: ASan checks the buffer holds them */
    volatile unsigned char sink = ((unsigned char *)v->data)[0];
    sink = ((unsigned char *)v->data)[n * vv_voxel_type_size(v->type) - 1];
    (void)sink;
    vv_volume_free(v);
}

void
fuzz_check_status(int status) {
    static int verbose = -1;
    if (verbose < 0)
        verbose = getenv("FUZZ_VERBOSE") != NULL;
    if (verbose) /* to see what a seed reaches: FUZZ_VERBOSE=1 fuzz_<format> SEED */
        fprintf(stderr, "fuzz: %s\n", status == 0 ? "ok" : vv_error_message());
    if (status > 0)
        __builtin_trap(); /* a status is VV_OK or a negative error */
    if (status < 0) {
        const char *m = vv_error_message();
        if (!m[0] || strchr(m, '\n'))
            __builtin_trap(); /* an error is one line, never empty */
    }
}

/* A box of at most 10^3 voxels from a third into every level, and the
 * coarsest level's proxy. */
void
fuzz_read_source(vv_source *s) {
    const int n = vv_source_levels(s);
    for (int l = 0; l < n; l++) {
        const vv_volume *h = vv_source_level(s, l);
        if (!h)
            __builtin_trap(); /* a level the source counts has a header */
        int lo[3], hi[3];
        for (int a = 0; a < 3; a++) {
            lo[a] = h->dims[a] / 3;
            hi[a] = h->dims[a] - 1 < lo[a] + 9 ? h->dims[a] - 1 : lo[a] + 9;
        }
        vv_volume *v = NULL;
        const vv_status st = vv_source_read_box(s, l, lo, hi, &v);
        fuzz_check_status(st);
        if (st == VV_OK)
            fuzz_check_volume(v);
    }
    vv_volume *p = NULL;
    const vv_status st = vv_source_proxy(s, n - 1, &p);
    fuzz_check_status(st);
    if (st == VV_OK)
        fuzz_check_volume(p);
}

static void
rm_tree_at(const char *path, int depth) {
    DIR *d = depth < 16 ? opendir(path) : NULL;
    if (d) {
        struct dirent *e;
        char p[1024];
        while ((e = readdir(d)) != NULL) {
            if (!strcmp(e->d_name, ".") || !strcmp(e->d_name, ".."))
                continue;
            snprintf(p, sizeof p, "%s/%s", path, e->d_name);
            struct stat st;
            if (lstat(p, &st) == 0 && S_ISDIR(st.st_mode))
                rm_tree_at(p, depth + 1);
            else
                unlink(p);
        }
        closedir(d);
    }
    rmdir(path);
}

void
fuzz_rm_tree(const char *path) {
    rm_tree_at(path, 0);
}

/*
 * C helpers of the Python binding (compiled into volvis._volvis by cffi;
 * python/build_ffi.py). No algorithm of the library lives here: only the
 * progress state that Python polls while the library works with the GIL
 * released, and the content hash that tells whether a numpy array shared
 * with a volume was written since the last render.
 */
#include <stdint.h>
#include <stdlib.h>

/* Frees what the library returned from malloc (grid scalars, label sizes). */
static void
vvpy_free(void *p) {
    free(p);
}

/*
 * A progress callback target that never enters Python: the library's
 * worker threads store the fraction and read the cancel flag; the Python
 * thread that waits polls the fraction (for a callable or a tqdm bar) and
 * sets the flag on KeyboardInterrupt or when its callable asks to stop.
 */
typedef struct vvpy_progress_state {
    double fraction;
    int calls;
    int cancel;
} vvpy_progress_state;

static int
vvpy_progress_cb(void *user, double fraction) {
    vvpy_progress_state *s = user;
    __atomic_store(&s->fraction, &fraction, __ATOMIC_RELAXED);
    __atomic_add_fetch(&s->calls, 1, __ATOMIC_RELAXED);
    return __atomic_load_n(&s->cancel, __ATOMIC_RELAXED);
}

static vvpy_progress_state *
vvpy_progress_new(void) {
    return calloc(1, sizeof(vvpy_progress_state));
}

static void
vvpy_progress_free(vvpy_progress_state *s) {
    free(s);
}

static vv_progress
vvpy_progress_get(vvpy_progress_state *s) {
    vv_progress p;
    p.fn = vvpy_progress_cb;
    p.user = s;
    return p;
}

static double
vvpy_progress_fraction(const vvpy_progress_state *s) {
    double f;
    __atomic_load(&s->fraction, &f, __ATOMIC_RELAXED);
    return f;
}

static int
vvpy_progress_calls(const vvpy_progress_state *s) {
    return __atomic_load_n(&s->calls, __ATOMIC_RELAXED);
}

static void
vvpy_progress_cancel(vvpy_progress_state *s) {
    __atomic_store_n(&s->cancel, 1, __ATOMIC_RELAXED);
}

/*
 * A 64-bit content hash of n bytes: each 1 MiB chunk is folded word by word
 * with h = (h ^ w) * K, a bijection of h for every word, so changing any one
 * word always changes the chunk's hash; the chunk hashes are folded in order
 * the same way. Chunks are hashed in parallel (OpenMP); the result does not
 * depend on the thread count.
 */
#define VVPY_CHUNK ((size_t)1 << 20)
#define VVPY_K 0x9E3779B97F4A7C15ull

static uint64_t
vvpy_hash_chunk(const unsigned char *p, size_t n) {
    uint64_t h = 0xCBF29CE484222325ull ^ n;
    size_t i = 0;
    for (; i + 8 <= n; i += 8) {
        uint64_t w;
        __builtin_memcpy(&w, p + i, 8);
        h = (h ^ w) * VVPY_K;
    }
    for (; i < n; i++)
        h = (h ^ p[i]) * VVPY_K;
    return h ^ (h >> 29);
}

static uint64_t
vvpy_hash(const void *data, size_t n) {
    size_t nchunks = (n + VVPY_CHUNK - 1) / VVPY_CHUNK;
    if (nchunks <= 1)
        return vvpy_hash_chunk(data, n);
    uint64_t *hs = malloc(nchunks * sizeof *hs);
    if (!hs)
        return vvpy_hash_chunk(data, n);
    const unsigned char *p = data;
#pragma omp parallel for schedule(static)
    for (long c = 0; c < (long)nchunks; c++) {
        size_t off = (size_t)c * VVPY_CHUNK;
        size_t len = n - off < VVPY_CHUNK ? n - off : VVPY_CHUNK;
        hs[c] = vvpy_hash_chunk(p + off, len);
    }
    uint64_t h = 0xCBF29CE484222325ull;
    for (size_t c = 0; c < nchunks; c++)
        h = (h ^ hs[c]) * VVPY_K;
    free(hs);
    return h;
}

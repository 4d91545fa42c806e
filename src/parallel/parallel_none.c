/*
 * Distributed rendering in a build without MPI (include/volvis/parallel.h):
 * one rank, and vv_parallel_new says that MPI is missing. Compiled instead
 * of parallel.c when CMake finds no MPI or VOLVIS_WITH_MPI is off.
 */
#include <string.h>

#include "core/internal.h"
#include "volvis/parallel.h"

int
vv_parallel_available(void) {
    return 0;
}

int
vv_parallel_launched(void) {
    return 0;
}

vv_status
vv_parallel_init(int *argc, char ***argv, int *rank, int *size) {
    (void)argc;
    (void)argv;
    *rank = 0;
    *size = 1;
    return VV_OK;
}

void
vv_parallel_finalize(void) {
}

vv_status
vv_parallel_agree(vv_status s) {
    return s;
}

vv_status
vv_parallel_check_same(const void *data, size_t n, const char *what) {
    (void)data;
    (void)n;
    (void)what;
    return VV_OK;
}

vv_status
vv_parallel_broadcast(void *data, size_t n) {
    (void)data;
    (void)n;
    return VV_OK;
}

vv_status
vv_parallel_max(const double *value, double *out) {
    *out = *value;
    return VV_OK;
}

void
vv_parallel_options_init(vv_parallel_options *o) {
    memset(o, 0, sizeof *o);
    o->radix = 4;
}

vv_status
vv_parallel_new(vv_parallel **out, vv_renderer *ren, const vv_parallel_options *opt) {
    (void)ren;
    (void)opt;
    *out = NULL;
    return vv_error_set(VV_ERR_UNSUPPORTED,
                        "parallel: this build has no MPI (install libopenmpi-dev and rebuild)");
}

vv_renderer *
vv_parallel_renderer(vv_parallel *p) {
    (void)p;
    return NULL;
}

void
vv_parallel_free(vv_parallel *p) {
    (void)p;
}

vv_status
vv_parallel_render(vv_parallel *p, const vv_world *w, const vv_view *view,
                   const vv_render_options *opt, vv_image *out, vv_parallel_stats *stats) {
    (void)p;
    (void)w;
    (void)view;
    (void)opt;
    (void)out;
    (void)stats;
    return vv_error_set(VV_ERR_UNSUPPORTED, "parallel: this build has no MPI");
}

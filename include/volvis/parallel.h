/*
 * VolVis distributed rendering over MPI: sort-last parallel volume
 * rendering (src/parallel, an optional build: on when CMake finds MPI).
 *
 * Each rank keeps one brick of the volume (a box cut at multiples of 16
 * voxels, with ghost voxels so that interpolation and gradients are those
 * of the whole volume) and renders it as one region of any renderer with
 * the region contract (include/volvis/sys/renderer.h: raycast, raytrace)
 * in the whole volume's frame; the partial images (premultiplied colour,
 * opacity, depth, and for maximum/minimum intensity projection the
 * projected value as the key) are composited in visibility order by binary swap (Ma,
 * Painter, Hansen and Krogh, "Parallel Volume Rendering Using Binary-Swap
 * Compositing", IEEE CG&A 1994; a count of ranks that is not a power of two
 * first folds the extra ranks into partners) or radix-k (Peterka, Goodell,
 * Ross, Shen and Thakur, "A Configurable Algorithm for Parallel
 * Image-Compositing Applications", SC 2009; rounds of k-way direct send for
 * any factorisation of the rank count), then gathered to rank 0. All ranks
 * use MPI_COMM_WORLD. docs/parallel.md describes the method and its costs.
 *
 * Thread-safety: MPI is initialised for funnelled use: call these functions
 * from the main thread only. Built without MPI, vv_parallel_init reports one
 * rank and vv_parallel_render fails with VV_ERR_UNSUPPORTED.
 */
#ifndef VOLVIS_PARALLEL_H
#define VOLVIS_PARALLEL_H

#include "core.h"
#include "image.h"
#include "io.h"
#include "model.h"
#include "render.h"

#ifdef __cplusplus
extern "C" {
#endif

/** 1 when the library was built with MPI. */
int vv_parallel_available(void);

/**
 * Whether this process was started by an MPI launcher (mpirun, mpiexec:
 * the environment says so); cheap, does not initialise MPI.
 */
int vv_parallel_launched(void);

/**
 * Initialises MPI (MPI_Init_thread, funnelled) unless already done; safe to
 * call once per process. *rank and *size receive this rank and the rank
 * count (0 and 1 without MPI). Errors: VV_ERR_IO (MPI failed to start).
 */
vv_status vv_parallel_init(int *argc, char ***argv, int *rank, int *size);

/** Finalises MPI if vv_parallel_init started it. */
void vv_parallel_finalize(void);

/**
 * Collective: every rank passes its own status @p s; returns VV_OK when all
 * are VV_OK, else on every rank the error of the lowest failing rank with
 * its message ("rank 2: ..."), so that all ranks stop together instead of
 * some waiting forever for the failed one.
 */
vv_status vv_parallel_agree(vv_status s);

/**
 * Collective: checks that @p n bytes at @p data (a scene file, the command
 * line) hash alike on every rank (FNV-1a 64, rank 0's broadcast); else
 * VV_ERR_INVALID on every rank: "ranks disagree on WHAT".
 */
vv_status vv_parallel_check_same(const void *data, size_t n, const char *what);

/**
 * Collective: copies @p n bytes at @p data from rank 0 to every rank.
 * Errors: VV_ERR_IO (MPI failed).
 */
vv_status vv_parallel_broadcast(void *data, size_t n);

/**
 * Collective: *out on rank 0 = the largest *value over the ranks (others:
 * unchanged). Errors: VV_ERR_IO.
 */
vv_status vv_parallel_max(const double *value, double *out);

/** Compositing methods. */
typedef enum vv_compositing {
    VV_COMPOSITING_BINARY_SWAP = 0,
    VV_COMPOSITING_RADIX_K = 1,
} vv_compositing;

/** Options of vv_parallel_render. */
typedef struct vv_parallel_options {
    vv_compositing method; /**< binary swap (default) or radix-k */
    int radix;             /**< radix-k: the largest group size k (default 4, >= 2) */
    int barrier;           /**< 1: wait for every rank between rendering and compositing
                                (compositing time without the render imbalance) */
} vv_parallel_options;

/** binary swap, radix 4, no barrier. */
void vv_parallel_options_init(vv_parallel_options *o);

/** Times of the last frame, seconds, this rank's (see also the max fields). */
typedef struct vv_parallel_stats {
    int ranks;
    double render;                /**< this rank's brick render */
    double render_cpu;            /**< CPU seconds of this rank's brick render, all its threads */
    double wait;                  /**< barrier (with options.barrier) */
    double composite;             /**< compositing rounds (including the fold) */
    double gather;                /**< gather to rank 0 */
    double max_render;            /**< the largest render time over the ranks (rank 0 only) */
    double max_composite;         /**< the largest compositing time over the ranks (rank 0 only) */
    double max_render_cpu;        /**< the largest render_cpu over the ranks (rank 0 only) */
    size_t brick_voxels;          /**< voxels this rank keeps, ghosts included */
    int brick_lo[3], brick_hi[3]; /**< this rank's box, voxel indices (inclusive) */
} vv_parallel_stats;

/** A renderer state for distributed rendering, kept between frames. */
typedef struct vv_parallel vv_parallel;

/**
 * A distributed renderer drawing with renderer @p ren (borrowed: keep it
 * alive until vv_parallel_free; its options, vv_renderer_set_option, apply;
 * it must declare VV_RENDERER_REGION), or with a raycast renderer of its
 * own when @p ren is NULL. @p opt may be NULL (defaults). Not collective.
 * Errors: VV_ERR_UNSUPPORTED (built without MPI, or MPI not initialised),
 * VV_ERR_INVALID (@p ren renders no regions), VV_ERR_NOMEM.
 */
vv_status vv_parallel_new(vv_parallel **out, vv_renderer *ren, const vv_parallel_options *opt);
/** The renderer it uses; borrowed. */
vv_renderer *vv_parallel_renderer(vv_parallel *p);
/**
 * Frees the context, its bricks and images, and the renderer it created
 * (not one passed to vv_parallel_new). NULL: nothing. Not collective.
 */
void vv_parallel_free(vv_parallel *p);

/**
 * Collective: renders @p w (one visible volume object, composite, mip or
 * minip; the same World on every rank) through @p view. Each rank cuts its
 * brick from the object's volume, or reads only its box from the object's
 * source when the object shows a file out of core (vv_object_new_source:
 * a bricked file, or a pyramid's level opt->lod->level, 0 without one; a
 * source opened without the range, vv_open_options.header_only, learns it from
 * the ranks' bricks at the first render); the brick is kept between frames
 * while the volume is unchanged. It renders the brick as a region (the
 * World, with the object's own volume, is the renderer's context: raytrace
 * traces its shadows through it, exactly when it is the whole volume, from
 * the proxy out of core), and the partial images are composited; rank 0
 * receives the whole image in @p out (view->width x view->height, RGBA
 * float and depth, as vv_renderer_render draws it; a region is traced one
 * ray a pixel, so raytrace gives its quality-1 sampling), the other ranks leave
 * @p out untouched (it may be NULL there). @p stats may be NULL. A failure
 * on any rank fails every rank (vv_parallel_agree). Errors:
 * VV_ERR_UNSUPPORTED (other objects or modes), VV_ERR_LIMIT (a volume too
 * small to cut for this many ranks), VV_ERR_NOMEM, those of the renderer.
 */
vv_status vv_parallel_render(vv_parallel *p, const vv_world *w, const vv_view *view,
                             const vv_render_options *opt, vv_image *out, vv_parallel_stats *stats);

#ifdef __cplusplus
}
#endif
#endif

/*
 * VolVis compression: the .vvc block-transform volume codec, a 3-D
 * generalisation of baseline JPEG with a discrete Fourier transform in place
 * of the cosine transform (Chiueh, He, Kaufman, Pfister et al., "Compression
 * Domain Volume Rendering", 1994/1997). The `fourier` renderer projects
 * straight from its coefficients (docs/rendering.md); the file format is in
 * docs/file-formats.md.
 *
 * Method. The volume is cut into M x M x M subcubes (M = 8, 16 or 32; edge
 * subcubes are padded with the volume's minimum). Values are coded as
 * (value - offset) / unit, offset = the minimum of the volume, unit = 1 for
 * integer data spanning at most 65535 and range / 65535 otherwise (float
 * data; integer data with a wider span), so a "grey level" is one unit.
 * Each subcube goes through a real-to-complex 3-D DFT (FFTW; plans made once
 * per codec object and reused), every coefficient is divided by a step from
 * a frequency-dependent quantisation table scaled by the quality and
 * rounded, the M^3 independent real numbers (Hermitian duplicates left out)
 * are ordered by increasing frequency (a 3-D zig-zag) and entropy coded as
 * in baseline JPEG: the DC term by its size category, the rest as (zero run,
 * size) symbols with EOB and ZRL, Huffman coded with canonical codes whose
 * tables are stored in the file, followed by the amplitude bits. Every
 * subcube's bit stream is byte-aligned and listed in a subcube index, so one
 * subcube decodes alone. Each section of the file carries a CRC-32: a
 * corrupt or truncated file gives VV_ERR_FORMAT, never garbage.
 *
 * Quality q in [0, 100]: the step of the unitary DFT coefficient (F / M^1.5)
 * at folded frequency (fx, fy, fz) is  s(q) * (1 + b(q) * |f| / (M/2)),
 * with s(q) = 0.5 / M^1.5 * 2^((100 - q) / 5) grey levels (each 5 points of
 * quality halve the step, about +6 dB) and b(q) = slope * min(1, (100 - q)
 * / 20). At q = 100 the table is flat and the unnormalised coefficients
 * have step 0.5, so no voxel can move by more than 0.354 grey levels, even
 * when the coefficients' rounding errors line up: integer data within 16
 * bits decode exactly. A target bit rate is met by a bracketed search on q (the size
 * of every candidate file follows from its symbol statistics, without
 * writing it; the byte padding of each subcube is counted as 7 bits, so the
 * file is never over the rate).
 *
 * Ownership: a vv_vvc holds the whole encoded file in memory plus its parsed
 * header, tables and index; vv_vvc_free releases it. Thread-safety: a vv_vvc
 * is immutable after creation; every decode function may be called from
 * many threads at once on the same object.
 */
#ifndef VOLVIS_COMPRESS_H
#define VOLVIS_COMPRESS_H

#include <stddef.h>
#include <stdint.h>

#include "core.h"
#include "volume.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Current .vvc format version (written by default); versions 1 and 2 are read. */
#define VV_VVC_VERSION 2

/** What the quality setting aims at. */
typedef enum vv_vvc_target {
    VV_VVC_QUALITY = 0,  /**< a quality factor in [0, 100] */
    VV_VVC_RATE = 1,     /**< a file size in bits per voxel, reached by searching the quality */
    VV_VVC_MAX_ERROR = 2 /**< |x - decoded x| <= max_error for every voxel (version 2 only) */
} vv_vvc_target;

/** Parameters of vv_vvc_compress. */
typedef struct vv_vvc_params {
    int block;            /**< subcube side M: 8, 16 or 32 */
    vv_vvc_target target; /**< quality or rate */
    double quality;       /**< [0, 100] for VV_VVC_QUALITY */
    double rate;          /**< bits per voxel (> 0) for VV_VVC_RATE, whole file included */
    double slope;         /**< frequency dependence of the table, >= 0 (0: flat) */
    double max_error;     /**< the bound (value units, > 0) for VV_VVC_MAX_ERROR */
    int version;          /**< format to write: 0 = VV_VVC_VERSION, 1 = legacy (Huffman) */
    int threads;          /**< <= 0: vv_threads_get() */
    vv_progress progress; /**< fraction of the work done; may cancel */
} vv_vvc_params;

/** Block 16, quality 75, rate 1, slope 0.5, max_error 1, version 0, threads 0, no progress. */
void vv_vvc_params_init(vv_vvc_params *p);

/** A compressed volume held in memory (see the file comment). */
typedef struct vv_vvc vv_vvc;

/** What a .vvc holds, from its header. */
typedef struct vv_vvc_info {
    int version;
    int dims[3];        /**< voxels of the original volume */
    vv_voxel_type type; /**< native voxel type restored on decompression */
    double spacing[3], origin[3], direction[9];
    vv_unit unit;
    vv_data_origin data_origin;
    vv_modification modification;
    vv_space space;
    double range[2];       /**< value range of the original volume */
    double value_offset;   /**< coded value = (value - value_offset) / value_unit */
    double value_unit;     /**< one grey level */
    int block;             /**< subcube side M */
    int subcubes[3];       /**< subcubes along i, j, k (dims rounded up to M) */
    double quality;        /**< quality the file was coded with */
    double slope;          /**< table slope the file was coded with */
    double max_error;      /**< guaranteed bound of |x - decoded x| (0: none; version 2) */
    double corr_step;      /**< value step of the voxel corrections (0: none; version 2) */
    uint64_t file_bytes;   /**< size of the whole file */
    uint64_t data_bytes;   /**< bytes of subcube bit streams */
    uint64_t raw_bytes;    /**< dims product * voxel size (the uncompressed data) */
    double ratio;          /**< raw_bytes / file_bytes */
    double bits_per_voxel; /**< 8 * file_bytes / voxels */
} vv_vvc_info;

/**
 * Compresses @p v (borrowed) into a new in-memory .vvc. NaN voxels are coded
 * as the minimum. For VV_VVC_RATE the quality is searched (regula falsi) so
 * that the file is at most the rate (the closest quality reachable when the
 * rate is out of reach; check the info). Errors: VV_ERR_INVALID (block not 8,
 * 16 or 32, quality outside [0, 100], rate <= 0, slope < 0 or a volume whose
 * range was not computed), VV_ERR_NOMEM, VV_ERR_CANCELLED.
 */
vv_status vv_vvc_compress(vv_vvc **out, const vv_volume *v, const vv_vvc_params *p);

/**
 * Parses and checks an encoded .vvc in memory (copied): magic, version,
 * every section's CRC-32, sizes, tables and the subcube index. @p name is
 * used in messages (may be NULL). Errors: VV_ERR_FORMAT (corrupt, truncated,
 * not a .vvc, unknown version), VV_ERR_LIMIT (absurd sizes), VV_ERR_NOMEM.
 */
vv_status vv_vvc_from_memory(vv_vvc **out, const void *data, size_t size, const char *name);

/** Reads and checks a .vvc file (as vv_vvc_from_memory). Errors: also VV_ERR_IO. */
vv_status vv_vvc_load(vv_vvc **out, const char *path);

/** Writes the encoded bytes to @p path atomically. Errors: VV_ERR_IO. */
vv_status vv_vvc_save(const vv_vvc *c, const char *path);

/** The encoded file bytes (owned by @p c) and their count. */
const unsigned char *vv_vvc_bytes(const vv_vvc *c, size_t *size);

/** Fills @p info from the header. */
void vv_vvc_get_info(const vv_vvc *c, vv_vvc_info *info);

/** 1 when @p path starts with the .vvc magic number, else 0 (also when unreadable). */
int vv_vvc_detect(const char *path);

/**
 * Decodes the whole volume: entropy decoding, dequantisation and an inverse
 * 3-D DFT per subcube, values converted back (rounded and clamped) to the
 * native voxel type; header fields are restored exactly and range[] is
 * recomputed. Errors: VV_ERR_FORMAT (a bit stream that does not decode),
 * VV_ERR_NOMEM, VV_ERR_CANCELLED.
 */
vv_status vv_vvc_decompress(vv_volume **out, const vv_vvc *c, int threads,
                            const vv_progress *progress);

/**
 * The r2c spectrum of every M^3 subcube of @p v (M = 8, 16 or 32, as a
 * .vvc's subcube size), unquantised: the coded values (value - offset) /
 * unit with the padding of edge subcubes at 0 (i.e. the minimum), each in
 * the layout of vv_vvc_decode_spectrum, subcubes in index order:
 * n * 2 * M * M * (M/2 + 1) floats in *spectra, allocated with FFTW's
 * fftwf_malloc (free with fftwf_free); *offset and *unit receive the value
 * scale. This is what a .vvc codes before its quantiser; the Fourier
 * renderer (compression-domain rendering, paper section 4.6) slices it
 * directly. Runs on @p threads threads (0: all). Errors: VV_ERR_INVALID,
 * VV_ERR_NOMEM, VV_ERR_CANCELLED.
 */
vv_status vv_vvc_spectra(const vv_volume *v, int M, int threads, float **spectra, double *offset,
                         double *unit, const vv_progress *progress);

/**
 * FFTW's planner is not thread-safe: the library makes and destroys every
 * FFTW plan between vv_fftw_lock() and vv_fftw_unlock() (a process-wide
 * mutex). A program that plans its own FFTW transforms while VolVis runs
 * in other threads takes the same lock around its planner calls.
 */
void vv_fftw_lock(void);
void vv_fftw_unlock(void);

/** Number of subcubes (subcubes[0] * subcubes[1] * subcubes[2]); index = (z * ny + y) * nx + x. */
int vv_vvc_subcube_count(const vv_vvc *c);

/**
 * Entropy-decodes and dequantises subcube @p index alone (nothing else of
 * the file is touched): the r2c spectrum of its coded values in FFTW's
 * layout, M x M x (M/2 + 1) complex numbers as interleaved float pairs
 * (re, im), index ((kz * M + ky) * (M/2 + 1) + kx), unnormalised
 * (F(k) = sum over x of f(x) e^{-2 pi i k.x / M}, x = i fastest), including
 * the Hermitian duplicates of the kx = 0 and kx = M/2 planes. @p spectrum
 * holds 2 * M * M * (M/2 + 1) floats. Errors: VV_ERR_INVALID (index out of
 * range), VV_ERR_FORMAT (a bit stream that does not decode).
 */
vv_status vv_vvc_decode_spectrum(const vv_vvc *c, int index, float *spectrum);

/**
 * Decodes subcube @p index alone to voxel values (in value units, not
 * rounded to the native type): M^3 floats, i fastest, the padding of edge
 * subcubes included. Errors as vv_vvc_decode_spectrum, VV_ERR_NOMEM.
 */
vv_status vv_vvc_decode_subcube(const vv_vvc *c, int index, float *values);

/** Releases a compressed volume. Accepts NULL. */
void vv_vvc_free(vv_vvc *c);

/**
 * Compares two volumes of equal dimensions voxel by voxel in double:
 * PSNR = 10 log10(peak^2 / MSE) with peak = max - min of @p ref (INFINITY for
 * equal volumes; the same definition as ../shared/anchors/bench_zfp.sh),
 * the root-mean-square and the maximum absolute error. Any output may be
 * NULL. Errors: VV_ERR_INVALID (dimensions differ).
 */
vv_status vv_volume_compare(const vv_volume *ref, const vv_volume *test, double *psnr, double *rmse,
                            double *max_error);

#ifdef __cplusplus
}
#endif
#endif

/*
 * bench_compress: the .vvc codec and the compression-domain `fourier`
 * renderer against their peers, printed as
 *   anchor=volvis op=<op> dataset=<file> value=<number> unit=<unit>
 * for ../shared/anchors/summarize.py, beside ../shared/anchors/bench_zfp.sh.
 *
 * Per rate R (bits per voxel, the whole file): vvc_rateR_psnr (dB, peak =
 * max - min of the data, as bench_zfp.sh), _rmse, _maxerr, _bits_per_voxel
 * (reached), _quality, compress and decompress wall time and throughput
 * (MB/s of the volume's native voxels; also Mvoxel/s) at the quality the
 * rate search found, and _search_wall (the search plus the final coding).
 * Then the fourier renderer against the ray caster's X-ray mode (the
 * spatial reference) at 512 x 512, orthographic, both taking the mean value
 * along the ray through the same linear grey ramp, from the minimum to the
 * brightest mean of the X-ray image: xray_frame, fourier_frame
 * (median of --runs after a first frame), fourier_first_frame (transforms
 * and oversampling included), the image agreement fourier_xray_psnr, and
 * per rate fourier_rateR_psnr and fourier_rateR_frame (rendering from the
 * compressed file against the spatial X-ray; all-zero subcubes, such as
 * quantised air, are skipped, so these frames are faster). With --zfp FILE (bench_zfp.sh output) a
 * cairo plot of both rate-distortion curves is written to OUTDIR/rate_distortion.png.
 * With --max-errors E1,E2,... the error-bound mode per bound E:
 * vvc_maxerrE_{bits_per_voxel,psnr,maxerr,compress_*,decompress_*} (compare
 * with bench/zfp_accuracy.sh, zfp's fixed-accuracy mode). --format 1 codes
 * the legacy format. fourier_memory_mb / fourier_memory_ratio: the growth of
 * the resident set over the first fourier frame (spectra, oversampled
 * spectra for the viewing axis, scratch) in MB and per MB of the volume.
 *
 * usage: bench_compress VOLUME [--runs N] [--threads N] [--size N] [--block M]
 *                       [--rates 0.5,1,2,4] [--max-errors 1,10] [--format 1|2]
 *                       [--zfp ZFP.txt] [--outdir DIR] [--azimuth DEG] [--elevation DEG]
 */
#include <cairo.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "util.h"
#include "volvis/volvis.h"

static const char *dataset;
#define emit(op, value, unit) bench_emit(op, dataset, value, unit)

/* Resident set size in MB (/proc/self/statm). */
static double
rss_mb(void) {
    FILE *f = fopen("/proc/self/statm", "r");
    long pages = 0, res = 0;
    if (f) {
        if (fscanf(f, "%ld %ld", &pages, &res) != 2)
            res = 0;
        fclose(f);
    }
    return (double)res * (double)sysconf(_SC_PAGESIZE) / 1e6;
}

/* Parses "a,b,c" into at most max numbers. */
static int
parse_list(const char *v, double *out, int max) {
    int n = 0;
    for (const char *p = v; *p && n < max;) {
        char *end;
        out[n++] = strtod(p, &end);
        if (end == p)
            break;
        p = *end == ',' ? end + 1 : end;
    }
    return n;
}

/* "0.5" -> "0.5", 1 -> "1": the rate as bench_zfp.sh names it. */
static void
rate_name(double r, char *buf, size_t n) {
    snprintf(buf, n, "%g", r);
}

#define MAX_RATES 16

typedef struct curve {
    int n;
    double rate[MAX_RATES], psnr[MAX_RATES];
} curve;

/* Reads "op=zfp_rateR_psnr ... value=V" lines. */
static void
read_zfp(const char *path, curve *z) {
    memset(z, 0, sizeof *z);
    FILE *f = fopen(path, "r");
    if (!f) {
        fprintf(stderr, "bench_compress: cannot read %s\n", path);
        return;
    }
    char line[1024];
    while (fgets(line, sizeof line, f) && z->n < MAX_RATES) {
        const char *op = strstr(line, "op=zfp_rate"), *val = strstr(line, "value=");
        if (!op || !val)
            continue;
        char *end;
        double r = strtod(op + 11, &end);
        if (strncmp(end, "_psnr ", 6) != 0)
            continue;
        z->rate[z->n] = r;
        z->psnr[z->n] = strtod(val + 6, NULL);
        z->n++;
    }
    fclose(f);
}

static void
plot(const char *path, const curve *v, const curve *z, const curve *fo) {
    const int W = 720, H = 480, L = 70, R = 20, T = 40, B = 60;
    cairo_surface_t *s = cairo_image_surface_create(CAIRO_FORMAT_RGB24, W, H);
    cairo_t *cr = cairo_create(s);
    cairo_set_source_rgb(cr, 1, 1, 1);
    cairo_paint(cr);
    double xmin = 0.25, xmax = 16, ymin = 1e9, ymax = -1e9;
    const curve *cs[3] = {v, z, fo};
    for (int c = 0; c < 3; c++)
        for (int i = 0; c < 3 && cs[c] && i < cs[c]->n; i++) {
            if (!isfinite(cs[c]->psnr[i]))
                continue;
            ymin = cs[c]->psnr[i] < ymin ? cs[c]->psnr[i] : ymin;
            ymax = cs[c]->psnr[i] > ymax ? cs[c]->psnr[i] : ymax;
            xmin = cs[c]->rate[i] < xmin ? cs[c]->rate[i] : xmin;
            xmax = cs[c]->rate[i] > xmax ? cs[c]->rate[i] : xmax;
        }
    ymin = floor(ymin / 10) * 10;
    ymax = ceil(ymax / 10) * 10;
    if (!(ymax > ymin))
        ymax = ymin + 10;
    const double lx0 = log2(xmin), lx1 = log2(xmax);
#define PX(r) (L + (log2(r) - lx0) / (lx1 - lx0) * (W - L - R))
#define PY(p) (H - B - ((p)-ymin) / (ymax - ymin) * (H - T - B))
    cairo_select_font_face(cr, "sans-serif", CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_NORMAL);
    cairo_set_font_size(cr, 12);
    cairo_set_line_width(cr, 1);
    char buf[64];
    for (double r = xmin; r <= xmax * 1.001; r *= 2) {
        cairo_set_source_rgb(cr, 0.85, 0.85, 0.85);
        cairo_move_to(cr, PX(r), T);
        cairo_line_to(cr, PX(r), H - B);
        cairo_stroke(cr);
        cairo_set_source_rgb(cr, 0, 0, 0);
        snprintf(buf, sizeof buf, "%g", r);
        cairo_move_to(cr, PX(r) - 8, H - B + 16);
        cairo_show_text(cr, buf);
    }
    for (double p = ymin; p <= ymax + 1e-9; p += 10) {
        cairo_set_source_rgb(cr, 0.85, 0.85, 0.85);
        cairo_move_to(cr, L, PY(p));
        cairo_line_to(cr, W - R, PY(p));
        cairo_stroke(cr);
        cairo_set_source_rgb(cr, 0, 0, 0);
        snprintf(buf, sizeof buf, "%g", p);
        cairo_move_to(cr, L - 30, PY(p) + 4);
        cairo_show_text(cr, buf);
    }
    cairo_set_source_rgb(cr, 0, 0, 0);
    cairo_rectangle(cr, L, T, W - L - R, H - T - B);
    cairo_stroke(cr);
    cairo_move_to(cr, W / 2 - 80, H - 20);
    cairo_show_text(cr, "rate (bits per voxel, log scale)");
    cairo_save(cr);
    cairo_move_to(cr, 20, H / 2 + 60);
    cairo_rotate(cr, -VV_PI / 2);
    cairo_show_text(cr, "PSNR (dB, peak = value range)");
    cairo_restore(cr);
    cairo_set_font_size(cr, 14);
    snprintf(buf, sizeof buf, "rate-distortion, %s", dataset);
    cairo_move_to(cr, L, 24);
    cairo_show_text(cr, buf);
    const double col[3][3] = {{0.8, 0.1, 0.1}, {0.1, 0.3, 0.8}, {0.1, 0.6, 0.2}};
    const char *names[3] = {"vvc (VolVis, volume PSNR)", "zfp 1.0 fixed rate (volume PSNR)",
                            "fourier image vs spatial X-ray (image PSNR)"};
    int legend = 0;
    for (int c = 0; c < 3; c++) {
        if (!cs[c] || cs[c]->n == 0)
            continue;
        cairo_set_source_rgb(cr, col[c][0], col[c][1], col[c][2]);
        cairo_set_line_width(cr, 2);
        int first = 1;
        for (int i = 0; i < cs[c]->n; i++) {
            if (!isfinite(cs[c]->psnr[i]))
                continue;
            if (first)
                cairo_move_to(cr, PX(cs[c]->rate[i]), PY(cs[c]->psnr[i]));
            else
                cairo_line_to(cr, PX(cs[c]->rate[i]), PY(cs[c]->psnr[i]));
            first = 0;
        }
        cairo_stroke(cr);
        for (int i = 0; i < cs[c]->n; i++) {
            if (!isfinite(cs[c]->psnr[i]))
                continue;
            cairo_arc(cr, PX(cs[c]->rate[i]), PY(cs[c]->psnr[i]), 4, 0, 2 * VV_PI);
            cairo_fill(cr);
        }
        cairo_set_font_size(cr, 12);
        cairo_move_to(cr, L + 12, T + 20 + 18 * legend);
        cairo_show_text(cr, names[c]);
        legend++;
    }
#undef PX
#undef PY
    cairo_destroy(cr);
    if (cairo_surface_write_to_png(s, path) != CAIRO_STATUS_SUCCESS)
        fprintf(stderr, "bench_compress: cannot write %s\n", path);
    cairo_surface_destroy(s);
}

static vv_image *
render(vv_renderer *r, const vv_world *w, int threads) {
    vv_image *img = NULL;
    if (vv_image_new(&img, w->view.width, w->view.height) != VV_OK)
        bench_die("bench_compress", "image");
    vv_render_options o;
    vv_render_options_init(&o);
    o.threads = threads;
    if (vv_renderer_render(r, w, &w->view, &o, img) != VV_OK)
        bench_die("bench_compress", vv_renderer_name(r));
    return img;
}

int
main(int argc, char **argv) {
    if (argc < 2) {
        fprintf(stderr, "usage: bench_compress VOLUME [--runs N] [--threads N] [--size N] "
                        "[--block M] [--rates 0.5,1,2,4] [--max-errors 1,10] [--format 1|2] "
                        "[--zfp ZFP.txt] [--outdir DIR] "
                        "[--azimuth DEG] [--elevation DEG]\n");
        return 2;
    }
    const char *path = argv[1], *zfp = NULL, *outdir = "build/bench-out";
    int runs = 5, threads = 0, size = 512, block = 16;
    double az = 30, el = 20;
    double rates[MAX_RATES] = {0.5, 1, 2, 4}, maxerrs[MAX_RATES];
    int nrates = 4, nmaxerrs = 0, format = 0;
    for (int i = 2; i < argc; i++) {
        const char *a = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
        if (!v) {
            fprintf(stderr, "bench_compress: %s needs a value\n", a);
            return 2;
        }
        i++;
        if (!strcmp(a, "--runs"))
            runs = atoi(v);
        else if (!strcmp(a, "--threads"))
            threads = atoi(v);
        else if (!strcmp(a, "--size"))
            size = atoi(v);
        else if (!strcmp(a, "--block"))
            block = atoi(v);
        else if (!strcmp(a, "--zfp"))
            zfp = v;
        else if (!strcmp(a, "--outdir"))
            outdir = v;
        else if (!strcmp(a, "--azimuth"))
            az = atof(v);
        else if (!strcmp(a, "--elevation"))
            el = atof(v);
        else if (!strcmp(a, "--rates"))
            nrates = parse_list(v, rates, MAX_RATES);
        else if (!strcmp(a, "--max-errors"))
            nmaxerrs = parse_list(v, maxerrs, MAX_RATES);
        else if (!strcmp(a, "--format"))
            format = atoi(v);
        else {
            fprintf(stderr, "bench_compress: unknown option %s\n", a);
            return 2;
        }
    }
    runs = runs < 1 ? 1 : runs;
    bench_mkdirs(outdir);
    dataset = strrchr(path, '/') ? strrchr(path, '/') + 1 : path;
    vv_volume *vol = NULL;
    if (vv_volume_load(&vol, path, NULL) != VV_OK)
        bench_die("bench_compress", path);
    const double mb =
        (double)vv_volume_voxel_count(vol) * (double)vv_voxel_type_size(vol->type) / 1e6;
    const double mvox = (double)vv_volume_voxel_count(vol) / 1e6;

    /* the shared view: orthographic 512^2, X-ray mean through a grey ramp
     * from the minimum to the brightest mean */
    vv_default_scene_options so;
    vv_default_scene_options_init(&so);
    so.mode = VV_MODE_XRAY;
    so.width = so.height = size;
    so.has_tf_range = 1;
    so.tf_lo = vol->range[0];
    so.tf_hi = vol->range[1];
    so.azimuth = vv_deg_to_rad(az);
    so.elevation = vv_deg_to_rad(el);
    vv_world *w = NULL;
    if (vv_world_new_for_volume(&w, vol, &so) != VV_OK)
        bench_die("bench_compress", "world");
    w->view.projection = VV_PROJECTION_ORTHOGRAPHIC;
    vv_view_frame_box(&w->view, vv_world_bounds(w));
    vv_renderer *rc = NULL, *fo = NULL;
    if (vv_renderer_new(&rc, "raycast") != VV_OK || vv_renderer_new(&fo, "fourier") != VV_OK)
        bench_die("bench_compress", "renderer");
    char bs[16];
    snprintf(bs, sizeof bs, "%d", block);
    if (vv_renderer_set_option(fo, "block", bs) != VV_OK)
        bench_die("bench_compress", "block");
    {
        vv_image *probe = render(rc, w, threads);
        float m = 0;
        for (int i = 0; i < size * size; i++)
            m = probe->rgba[4 * i] > m ? probe->rgba[4 * i] : m;
        vv_image_free(probe);
        m = sqrtf(m); /* the default grey ramp also ramps the colour: grey = t^2 */
        vv_object *obj = w->objects[0];
        vv_tf_set_ramp(&obj->tf, vol->range[0],
                       vol->range[0] + (vol->range[1] - vol->range[0]) * (m > 0 ? m : 1), 1.0,
                       vv_vec3_make(1, 1, 1), obj->tf.opacity_unit_distance);
    }
    /* frames, interleaved pairs */
    double *tx = malloc(sizeof(double) * (size_t)runs), *tf = malloc(sizeof(double) * (size_t)runs);
    const double rss0 = rss_mb();
    double t0 = bench_now();
    vv_image *fimg = render(fo, w, threads);
    emit("fourier_first_frame", bench_now() - t0, "s");
    emit("fourier_memory_mb", rss_mb() - rss0, "MB");
    emit("fourier_memory_ratio", (rss_mb() - rss0) / mb, "x volume");
    vv_image_free(fimg);
    vv_image *ximg = NULL;
    fimg = NULL;
    for (int r = 0; r < runs; r++) {
        vv_image_free(ximg);
        vv_image_free(fimg);
        t0 = bench_now();
        ximg = render(rc, w, threads);
        tx[r] = bench_now() - t0;
        t0 = bench_now();
        fimg = render(fo, w, threads);
        tf[r] = bench_now() - t0;
        fprintf(stderr, "pair %d: xray %.4f s, fourier %.4f s, ratio %.1f\n", r, tx[r], tf[r],
                tx[r] / tf[r]);
    }
    const double mx = bench_median(tx, runs), mf = bench_median(tf, runs);
    emit("xray_frame", mx, "s");
    emit("fourier_frame", mf, "s");
    emit("fourier_speedup", mx / mf, "x");
    const double agree = vv_image_psnr(ximg, fimg);
    emit("fourier_xray_psnr", agree, "dB");
    char png[1200];
    snprintf(png, sizeof png, "%s/%s_xray.png", outdir, dataset);
    vv_image_write_png(ximg, png, 1, 0);
    snprintf(png, sizeof png, "%s/%s_fourier.png", outdir, dataset);
    vv_image_write_png(fimg, png, 1, 0);
    vv_image_free(fimg);

    /* rates */
    curve vc = {0}, fc = {0};
    for (int i = 0; i < nrates; i++) {
        char rn[32], op[96];
        rate_name(rates[i], rn, sizeof rn);
        vv_vvc_params p;
        vv_vvc_params_init(&p);
        p.block = block;
        p.target = VV_VVC_RATE;
        p.rate = rates[i];
        p.threads = threads;
        p.version = format;
        vv_vvc *c = NULL;
        t0 = bench_now();
        if (vv_vvc_compress(&c, vol, &p) != VV_OK)
            bench_die("bench_compress", "compress");
        const double tsearch = bench_now() - t0;
        vv_vvc_info info;
        vv_vvc_get_info(c, &info);
        vv_vvc_free(c);
        /* timing at the quality found */
        p.target = VV_VVC_QUALITY;
        p.quality = info.quality;
        double tc[16], td[16];
        const int n = runs < 16 ? runs : 16;
        vv_volume *dec = NULL;
        for (int r = 0; r < n; r++) {
            t0 = bench_now();
            if (vv_vvc_compress(&c, vol, &p) != VV_OK)
                bench_die("bench_compress", "compress");
            tc[r] = bench_now() - t0;
            vv_volume_free(dec);
            t0 = bench_now();
            if (vv_vvc_decompress(&dec, c, threads, NULL) != VV_OK)
                bench_die("bench_compress", "decompress");
            td[r] = bench_now() - t0;
            if (r + 1 < n)
                vv_vvc_free(c);
        }
        double psnr, rmse, maxe;
        vv_volume_compare(vol, dec, &psnr, &rmse, &maxe);
        const double mtc = bench_median(tc, n), mtd = bench_median(td, n);
#define E(suffix, value, unit)                                                                     \
    do {                                                                                           \
        snprintf(op, sizeof op, "vvc_rate%s_%s", rn, suffix);                                      \
        emit(op, value, unit);                                                                     \
    } while (0)
        E("psnr", psnr, "dB");
        E("rmse", rmse, "value");
        E("maxerr", maxe, "value");
        E("bits_per_voxel", info.bits_per_voxel, "bits/voxel");
        E("quality", info.quality, "quality");
        E("search_wall", tsearch, "s");
        E("compress_wall", mtc, "s");
        E("decompress_wall", mtd, "s");
        E("compress_throughput", mb / mtc, "MB/s");
        E("decompress_throughput", mb / mtd, "MB/s");
        E("compress_mvoxels", mvox / mtc, "Mvoxel/s");
        E("decompress_mvoxels", mvox / mtd, "Mvoxel/s");
#undef E
        vc.rate[vc.n] = info.bits_per_voxel;
        vc.psnr[vc.n++] = psnr;
        /* render straight from this file */
        char fn[1200];
        snprintf(fn, sizeof fn, "%s/%s_rate%s.vvc", outdir, dataset, rn);
        if (vv_vvc_save(c, fn) != VV_OK)
            bench_die("bench_compress", fn);
        vv_vvc_free(c);
        vv_volume_free(dec);
        vv_renderer *fr = NULL;
        if (vv_renderer_new(&fr, "fourier") != VV_OK || vv_renderer_set_option(fr, "vvc", fn))
            bench_die("bench_compress", "fourier vvc");
        vv_image *img = render(fr, w, threads); /* decodes the file, oversamples */
        double tr[16];
        for (int r = 0; r < n; r++) {
            vv_image_free(img);
            t0 = bench_now();
            img = render(fr, w, threads);
            tr[r] = bench_now() - t0;
        }
        snprintf(op, sizeof op, "fourier_rate%s_frame", rn);
        emit(op, bench_median(tr, n), "s");
        const double fp = vv_image_psnr(ximg, img);
        snprintf(op, sizeof op, "fourier_rate%s_psnr", rn);
        emit(op, fp, "dB");
        snprintf(png, sizeof png, "%s/%s_fourier_rate%s.png", outdir, dataset, rn);
        vv_image_write_png(img, png, 1, 0);
        fc.rate[fc.n] = info.bits_per_voxel;
        fc.psnr[fc.n++] = fp;
        vv_image_free(img);
        vv_renderer_free(fr);
    }
    /* the error-bound mode */
    for (int i = 0; i < nmaxerrs; i++) {
        char en[32], op[96];
        snprintf(en, sizeof en, "%g", maxerrs[i]);
        vv_vvc_params p;
        vv_vvc_params_init(&p);
        p.block = block;
        p.target = VV_VVC_MAX_ERROR;
        p.max_error = maxerrs[i];
        p.threads = threads;
        double tc[16], td[16];
        const int n = runs < 16 ? runs : 16;
        vv_vvc *c = NULL;
        vv_volume *dec = NULL;
        for (int r = 0; r < n; r++) {
            vv_vvc_free(c);
            t0 = bench_now();
            if (vv_vvc_compress(&c, vol, &p) != VV_OK)
                bench_die("bench_compress", "compress (max error)");
            tc[r] = bench_now() - t0;
            vv_volume_free(dec);
            t0 = bench_now();
            if (vv_vvc_decompress(&dec, c, threads, NULL) != VV_OK)
                bench_die("bench_compress", "decompress");
            td[r] = bench_now() - t0;
        }
        vv_vvc_info info;
        vv_vvc_get_info(c, &info);
        double psnr, rmse, maxe;
        vv_volume_compare(vol, dec, &psnr, &rmse, &maxe);
        const double mtc = bench_median(tc, n), mtd = bench_median(td, n);
#define E(suffix, value, unit)                                                                     \
    do {                                                                                           \
        snprintf(op, sizeof op, "vvc_maxerr%s_%s", en, suffix);                                    \
        emit(op, value, unit);                                                                     \
    } while (0)
        E("bits_per_voxel", info.bits_per_voxel, "bits/voxel");
        E("psnr", psnr, "dB");
        E("maxerr", maxe, "value");
        E("compress_wall", mtc, "s");
        E("decompress_wall", mtd, "s");
        E("compress_throughput", mb / mtc, "MB/s");
        E("decompress_throughput", mb / mtd, "MB/s");
        E("compress_mvoxels", mvox / mtc, "Mvoxel/s");
        E("decompress_mvoxels", mvox / mtd, "Mvoxel/s");
#undef E
        vv_vvc_free(c);
        vv_volume_free(dec);
    }
    if (zfp) {
        curve zc;
        read_zfp(zfp, &zc);
        snprintf(png, sizeof png, "%s/rate_distortion.png", outdir);
        plot(png, &vc, &zc, &fc);
        fprintf(stderr, "bench_compress: wrote %s (%d vvc, %d zfp points)\n", png, vc.n, zc.n);
    }
    vv_image_free(ximg);
    free(tx);
    free(tf);
    vv_renderer_free(rc);
    vv_renderer_free(fo);
    vv_world_free(w);
    vv_volume_free(vol);
    return 0;
}

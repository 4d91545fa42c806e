/*
 * Shared set-up of the benchmark programs: the geometry renderer's benchmark
 * scene (../shared/BENCHMARKS.md's view of a volume's isosurface) and frame
 * frame timing (clocks and medians: util.h), used by bench_raster and
 * bench_surface so both print the same `raster_frame`.
 */
#ifndef VOLVIS_BENCH_SCENE_H
#define VOLVIS_BENCH_SCENE_H

#include "volvis/volvis.h"

/*
 * A World holding one volume object of vol (named name; the World takes a
 * reference to vol) and one white headlight, and nothing else set up.
 * *obj (may be NULL) receives the object. Errors: vv_error_set.
 */
vv_status vvb_volume_world(vv_world **w, vv_object **obj, vv_volume *vol, const char *name);

/*
 * The peers' placement and view of ../shared/BENCHMARKS.md: vol centred at
 * the origin with an identity direction (vol->modified is bumped); a
 * perspective view of width x height pixels, fov 20 degrees, eye at ext/2 *
 * 11 * normalize(1, -1.6, 1) (ext the longest world extent of vol) looking
 * at the origin with z up, black background, white ambient light; obj at
 * step 0.5 with Phong ka 0.1 kd 0.6 ks 0.3 n 30, white.
 */
void vvb_center(vv_volume *vol);
void vvb_peer_view(vv_world *w, vv_object *obj, int width, int height);

/*
 * Builds the benchmark World around vol for the `surface` renderer: vol is
 * centred at the origin with an identity direction (the peers' placement;
 * vol->modified is bumped), drawn as its isosurface at iso (mode iso,
 * Phong ka 0.1 kd 0.6 ks 0.3 n 30, white), one white headlight, black
 * background; perspective view of size x size pixels, fov 20 degrees, eye at
 * ext/2 * 11 * normalize(1, -1.6, 1) (ext the longest world extent of vol)
 * looking at the origin with z up. The World takes a reference to vol.
 * *obj (may be NULL) receives the volume object. Errors: vv_error_set.
 */
vv_status vvb_surface_world(vv_world **w, vv_object **obj, vv_volume *vol, double iso, int size);

/*
 * Renders runs frames of w's view with r and returns the median wall time;
 * *cpu (may be NULL) gets the median CPU time of the process per frame.
 * The image of the last frame stays in img. Errors: vv_error_set, *wall
 * untouched.
 */
vv_status vvb_median_frame(double *wall, double *cpu, vv_renderer *r, const vv_world *w,
                           const vv_render_options *opt, vv_image *img, int runs);

#endif

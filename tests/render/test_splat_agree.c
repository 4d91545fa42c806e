/*
 * Agreement of the splatting renderer with the ray caster at the same view,
 * transfer function and lights, on real and analytic volumes (issue 15):
 * PSNR of the 8-bit images, X-ray >= 40 dB, MIP >= 35 dB, shaded composite
 * >= 28 dB, on neghip.slc, the CT head (ct_head.nrrd) and a 128^3
 * Marschner-Lobb phantom. A separate executable from test_splat.c, which
 * holds the other checks, so that each stays short. Images go to
 * build/test-out/render_splat/.
 */
#include "splat_common.h"

/* ---------------------------------------------------------------------- */
/* Agreement with the ray caster                                            */

#if defined(__SANITIZE_ADDRESS__)
#define VT_SANITIZED 1
#else
#define VT_SANITIZED 0
#endif

/* Under the sanitizers (ten times slower) the agreement checks run at a
 * quarter of the pixels, the CT head in composite mode only, and report
 * without judging: the release build judges them. */
static void
check_agreement(vv_volume *v, const char *name, int size) {
    if (VT_SANITIZED)
        size /= 2;
    vv_world *w = scene_for(v, size, 30, 20);
    /* one renderer of each kind: their volume caches serve all three modes */
    vv_renderer *rc = new_r("raycast"), *sp = new_r("splat");
    char nm[128];
    snprintf(nm, sizeof nm, "%s_composite", name);
    const double pc = agreement_with(rc, sp, w, VV_MODE_COMPOSITE, nm);
    /* under the sanitizers, big volumes only in composite mode (MIP splats
     * every voxel) */
    const int all = !VT_SANITIZED || (double)v->dims[0] * v->dims[1] * v->dims[2] < 4e6;
    double pm = INFINITY, px = INFINITY;
    if (all) {
        snprintf(nm, sizeof nm, "%s_mip", name);
        pm = agreement_with(rc, sp, w, VV_MODE_MIP, nm);
        snprintf(nm, sizeof nm, "%s_xray", name);
        px = agreement_with(rc, sp, w, VV_MODE_XRAY, nm);
    }
    vv_renderer_free(rc);
    vv_renderer_free(sp);
    vv_world_free(w);
    if (VT_SANITIZED)
        return;
    if (!(pc >= 28))
        fail_msg("%s: shaded composite PSNR %.2f dB < 28", name, pc);
    if (!(pm >= 35))
        fail_msg("%s: MIP PSNR %.2f dB < 35", name, pm);
    if (!(px >= 40))
        fail_msg("%s: X-ray PSNR %.2f dB < 40", name, px);
}

static void
test_agree_neghip(void **state) {
    (void)state;
    if (!vt_have_data("volumes/neghip.slc"))
        vt_skip("../shared/data/volumes/neghip.slc is missing");
    vv_volume *v = NULL;
    vt_ok(vv_volume_load(&v, vt_data("volumes/neghip.slc"), NULL));
    check_agreement(v, "neghip", 128);
    vv_volume_free(v);
}

static void
test_agree_ct_head(void **state) {
    (void)state;
    if (!vt_have_data("volumes/ct_head.nrrd"))
        vt_skip("../shared/data/volumes/ct_head.nrrd is missing");
    vv_volume *v = NULL;
    vt_ok(vv_volume_load(&v, vt_data("volumes/ct_head.nrrd"), NULL));
    /* 256^2: at 128^2 a pixel spans two voxels, and the EWA filter, which
     * the ray caster lacks, dominates the difference */
    check_agreement(v, "ct_head", 256);
    vv_volume_free(v);
}

static void
test_agree_marschner_lobb(void **state) {
    (void)state;
    vv_volume *v = marschner_lobb(128);
    check_agreement(v, "ml128", 128);
    vv_volume_free(v);
}

int
main(int argc, char **argv) {
    if (argc > 1)
        cmocka_set_test_filter(argv[1]);
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_agree_neghip),
        cmocka_unit_test(test_agree_ct_head),
        cmocka_unit_test(test_agree_marschner_lobb),
    };
    return vt_run_tests(tests, NULL, NULL);
}

/* `volvis devices`: listing, --assign, --replay (run as a separate process). */
#include "testutil.h"

#include <stdio.h>
#include <string.h>

#define outdir() vt_outdir("cli-devices")
#define run_cli(...) vt_run_cli_v(outdir(), (const char *const[]){__VA_ARGS__, NULL})
#define DEVDIR VV_SOURCE_DIR "/share/devices"

static void
test_devices_cli(void **state) {
    (void)state;
    const char *cfg = vt_path(outdir(), "input.json");
    remove(cfg);
    vt_run_result r = run_cli("devices", "--no-probe", "--device-dir", DEVDIR, "--config", cfg);
    assert_int_equal(r.status, 0);
    assert_non_null(strstr(r.out, "device 1: keyboard"));
    assert_non_null(strstr(r.out, "device 2: mouse"));
    assert_non_null(strstr(r.out, "pointer-x [0, 32768] px"));
    vt_run_result_free(&r);

    r = run_cli("devices", "--assign", "mouse", "navigator", "--config", cfg);
    assert_int_equal(r.status, 0);
    vt_run_result_free(&r);
    r = run_cli("devices", "--no-probe", "--device-dir", DEVDIR, "--config", cfg);
    assert_non_null(strstr(r.out, "device 2: mouse (mouse, driver gui)\n  assigned to: navigator"));
    vt_run_result_free(&r);
    r = run_cli("devices", "--assign", "toaster", "navigator", "--config", cfg);
    assert_int_equal(r.status, 2);
    vt_run_result_free(&r);

    const char *rec = vt_path(outdir(), "click.vvin");
    const char *text = "volvis-input 1\ndevice 4 mouse m\n0 button 4 1 1\n0.1 button 4 1 0\n";
    vt_write_file(rec, text, strlen(text));
    r = run_cli("devices", "--replay", rec, "--device-dir", DEVDIR);
    assert_int_equal(r.status, 0);
    assert_non_null(strstr(r.out, "click     dev=3 button=1"));
    vt_run_result_free(&r);
    vt_write_file(rec, "volvis-input 1\ndevice 4 mouse m\nx\n", 33);
    r = run_cli("devices", "--replay", rec);
    assert_int_equal(r.status, 1);
    assert_non_null(strstr(r.err, "click.vvin: line 3:"));
    vt_run_result_free(&r);
}

int
main(void) {
    const struct CMUnitTest tests[] = {cmocka_unit_test(test_devices_cli)};
    return vt_run_tests(tests, NULL, NULL);
}

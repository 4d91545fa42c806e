/*
 * The messages of `volvis serve` (apps/volvis/serve/serve_msg.c): every
 * message type of docs/serve-protocol.md parses with its fields; every kind
 * of bad message (not JSON, not an object, unknown type or field, wrong
 * type, out of range, too long, control bytes, duplicate keys) is refused
 * with a reason naming the field; paths stay inside the root (absolute
 * paths, "..", links out of the root, a save over a folder or a link, a
 * save that is not .json are refused), through openat2 and through the
 * walk that replaces it on kernels without; URLs in normal form and the
 * allow list (no userinfo, no encoded or plain "..", prefixes on a
 * segment boundary); a scene's "file" entries stay inside the root.
 */
#define _GNU_SOURCE
#include "testutil.h"

#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "../apps/volvis/serve/serve.h"

static srv_msg m;
static char why[512];

static int
parse(const char *text) {
    why[0] = '\0';
    return srv_msg_parse(text, strlen(text), &m, why, sizeof why);
}

static void
refused(const char *text, const char *needle) {
    if (parse(text) == 0)
        fail_msg("accepted: %s", text);
    if (!strstr(why, needle))
        fail_msg("%s: reason '%s' lacks '%s'", text, why, needle);
    assert_null(strchr(why, '\n'));
}

static void
test_good(void **state) {
    (void)state;
    assert_int_equal(parse("{\"type\":\"hello\",\"width\":1000,\"height\":800}"), 0);
    assert_int_equal(m.type, SRV_HELLO);
    assert_int_equal(m.width, 1000);
    assert_int_equal(m.height, 800);
    assert_int_equal(
        parse("{\"type\":\"nav\",\"motion\":\"rotate\",\"dx\":3.5,\"dy\":-2,\"seq\":17,"
              "\"moving\":true}"),
        0);
    assert_int_equal(m.type, SRV_NAV);
    assert_int_equal(m.motion, VV_NAV_ROTATE);
    assert_true(m.dx == 3.5 && m.dy == -2 && m.seq == 17 && m.moving == 1);
    assert_int_equal(parse("{\"type\":\"nav\",\"motion\":\"zoom\",\"factor\":1.25}"), 0);
    assert_true(m.motion == VV_NAV_ZOOM && m.factor == 1.25 && m.moving == 0);
    assert_int_equal(parse("{\"type\":\"mode\",\"mode\":\"iso\",\"isovalue\":400}"), 0);
    assert_true(m.mode == VV_MODE_ISO && m.has_isovalue && m.isovalue == 400);
    assert_int_equal(parse("{\"type\":\"mode\",\"mode\":\"mip\"}"), 0);
    assert_true(m.mode == VV_MODE_MIP && !m.has_isovalue);
    assert_int_equal(parse("{\"type\":\"preset\",\"name\":\"ct-bone\"}"), 0);
    assert_string_equal(m.name, "ct-bone");
    assert_int_equal(parse("{\"type\":\"channel\",\"index\":1,\"visible\":false,"
                           "\"color\":\"#ff8000\"}"),
                     0);
    assert_true(m.index == 1 && m.has_visible && !m.visible && m.has_color);
    assert_true(fabs(m.color.x - 1) < 1e-12 && fabs(m.color.y - 128 / 255.0) < 1e-12 &&
                m.color.z == 0);
    assert_int_equal(parse("{\"type\":\"time\",\"step\":3}"), 0);
    assert_int_equal(m.index, 3);
    assert_int_equal(parse("{\"type\":\"slice\",\"axis\":\"coronal\",\"index\":5,\"width\":256,"
                           "\"height\":200,\"window\":400,\"level\":40}"),
                     0);
    assert_true(m.type == SRV_SLICE && m.axis == VV_SLICE_CORONAL && m.has_window &&
                m.window == 400 && m.level == 40 && m.width == 256 && m.height == 200);
    assert_int_equal(parse("{\"type\":\"probe\",\"axis\":\"sagittal\",\"index\":0,\"width\":64,"
                           "\"height\":64,\"x\":10.5,\"y\":3}"),
                     0);
    assert_true(m.type == SRV_PROBE && m.axis == VV_SLICE_SAGITTAL && m.x == 10.5);
    assert_int_equal(parse("{\"type\":\"png\"}"), 0);
    assert_int_equal(m.type, SRV_PNG);
    assert_int_equal(parse("{\"type\":\"thumbnails\"}"), 0);
    assert_int_equal(m.size, 96);
    assert_int_equal(parse("{\"type\":\"save\",\"path\":\"a/b.json\"}"), 0);
    assert_true(m.type == SRV_SAVE && strcmp(m.path, "a/b.json") == 0);
    assert_int_equal(parse("{\"type\":\"list\",\"path\":\"\"}"), 0);
    assert_int_equal(parse("{\"type\":\"reset_view\"}"), 0);
}

static void
test_bad(void **state) {
    (void)state;
    refused("", "not JSON");
    refused("garbage", "not JSON");
    refused("[1,2]", "not a JSON object");
    refused("{}", "'type' is missing");
    refused("{\"type\":7}", "'type' is not a string");
    refused("{\"type\":\"explode\"}", "unknown message type");
    refused("{\"type\":\"png\",\"extra\":1}", "unknown field 'extra'");
    refused("{\"type\":\"hello\",\"width\":1000}", "'height' is missing");
    refused("{\"type\":\"hello\",\"width\":1e9,\"height\":10}", "'width'");
    refused("{\"type\":\"hello\",\"width\":10.5,\"height\":100}", "not an integer");
    refused("{\"type\":\"hello\",\"width\":8,\"height\":100}", "outside");
    refused("{\"type\":\"nav\",\"motion\":\"spin\"}", "'motion'");
    refused("{\"type\":\"nav\",\"motion\":\"zoom\"}", "'factor' is missing");
    refused("{\"type\":\"nav\",\"motion\":\"zoom\",\"factor\":0}", "'factor'");
    refused("{\"type\":\"nav\",\"motion\":\"rotate\",\"dx\":\"a\"}", "'dx' is not a number");
    refused("{\"type\":\"nav\",\"motion\":\"rotate\",\"dx\":1e300}", "'dx'");
    refused("{\"type\":\"nav\",\"motion\":\"rotate\",\"seq\":-1}", "'seq'");
    refused("{\"type\":\"nav\",\"motion\":\"rotate\",\"moving\":1}", "'moving'");
    refused("{\"type\":\"mode\",\"mode\":\"xyz\"}", "'mode'");
    refused("{\"type\":\"preset\",\"name\":\"no-such\"}", "no preset");
    refused("{\"type\":\"channel\",\"index\":99}", "'index'");
    refused("{\"type\":\"channel\",\"index\":0,\"color\":\"red\"}", "'color'");
    refused("{\"type\":\"slice\",\"axis\":\"oblique\",\"index\":0,\"width\":64,\"height\":64}",
            "'axis'");
    refused("{\"type\":\"slice\",\"axis\":\"axial\",\"index\":0,\"width\":64,\"height\":64,"
            "\"window\":10}",
            "go together");
    refused("{\"type\":\"slice\",\"axis\":\"axial\",\"index\":0,\"width\":64,\"height\":64,"
            "\"window\":-1,\"level\":0}",
            "'window'");
    refused("{\"type\":\"save\",\"path\":\"a\\u0001b\"}", "control byte");
    refused("{\"type\":\"save\",\"path\":\"a\\u0000b\"}", "NUL");
    refused("{\"type\":\"png\",\"type\":\"png\"}", "not JSON");
    /* a path over the cap */
    char big[SRV_PATH_MAX + 64];
    int n = snprintf(big, sizeof big, "{\"type\":\"open\",\"path\":\"");
    memset(big + n, 'a', SRV_PATH_MAX);
    snprintf(big + n + SRV_PATH_MAX, sizeof big - (size_t)n - SRV_PATH_MAX, "\"}");
    refused(big, "longer than");
    /* a message over the cap, never parsed */
    size_t huge = SRV_MSG_MAX + 10;
    char *h = malloc(huge);
    assert_non_null(h);
    memset(h, ' ', huge);
    h[0] = '{';
    h[huge - 1] = '}';
    assert_int_equal(srv_msg_parse(h, huge, &m, why, sizeof why), -1);
    assert_non_null(strstr(why, "at most"));
    free(h);
    /* deep nesting */
    char deep[8192];
    size_t k = 0;
    k += (size_t)snprintf(deep, sizeof deep, "{\"type\":\"png\",\"x\":");
    for (int i = 0; i < 3000 && k < sizeof deep - 8; i++)
        deep[k++] = '[';
    deep[k] = '\0';
    assert_int_equal(srv_msg_parse(deep, k, &m, why, sizeof why), -1);
}

static char root[PATH_MAX];

static void
mk(const char *rel, int dir) {
    char p[PATH_MAX + 64];
    snprintf(p, sizeof p, "%s/%s", root, rel);
    if (dir)
        assert_int_equal(mkdir(p, 0755) == 0 || errno == EEXIST, 1);
    else
        vt_write_file(p, "x", 1);
}

static void
test_paths(void **state) {
    (void)state;
    const char *out = vt_outdir("serve_msg");
    char made[PATH_MAX + 16];
    snprintf(made, sizeof made, "%s/root", out);
    mkdir(made, 0755);
    assert_non_null(realpath(made, root));
    mk("sub", 1);
    mk("sub/a.nrrd", 0);
    mk("b.json", 0);
    mk("dir.json", 1);
    char link[PATH_MAX + 32];
    snprintf(link, sizeof link, "%s/out", root);
    unlink(link);
    assert_int_equal(symlink("/etc", link), 0);
    snprintf(link, sizeof link, "%s/passwd.json", root);
    unlink(link);
    assert_int_equal(symlink("/etc/passwd", link), 0);
    snprintf(link, sizeof link, "%s/sub/in", root);
    unlink(link);
    assert_int_equal(symlink("a.nrrd", link), 0);

    char full[PATH_MAX], w[256];
    assert_int_equal(srv_path_resolve(root, "sub/a.nrrd", 0, full, sizeof full, w, sizeof w), 0);
    assert_true(strncmp(full, root, strlen(root)) == 0);
    assert_int_equal(srv_path_resolve(root, "sub/in", 0, full, sizeof full, w, sizeof w), 0);
    assert_non_null(strstr(full, "sub/a.nrrd")); /* a link inside is followed */
    assert_int_equal(srv_path_resolve(root, "", 1, full, sizeof full, w, sizeof w), 0);
    assert_string_equal(full, root);
    assert_int_equal(srv_path_resolve(root, "sub/", 1, full, sizeof full, w, sizeof w), 0);

    static const struct {
        const char *rel;
        int kind;
        const char *needle;
    } bad[] = {
        {"/etc/passwd", 0, "absolute"},
        {"../x", 0, "'..'"},
        {"sub/../../x", 0, "'..'"},
        {"./sub", 0, "'.'"},
        {"sub//a.nrrd", 0, "empty"},
        {"out/passwd", 0, "leaves the root"},
        {"out", 1, "leaves the root"},
        {"missing.nrrd", 0, "No such file"},
        {"sub/a.nrrd", 1, "not a folder"},
        {"new.png", 2, ".json"},
        {"dir.json", 2, "not a regular file"},
        {"passwd.json", 2, "not a regular file"},
        {"out/x.json", 2, "leaves the root"},
        {"nofolder/x.json", 2, "its folder"},
    };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        w[0] = '\0';
        if (srv_path_resolve(root, bad[i].rel, bad[i].kind, full, sizeof full, w, sizeof w) == 0)
            fail_msg("accepted '%s' (kind %d)", bad[i].rel, bad[i].kind);
        if (!strstr(w, bad[i].needle))
            fail_msg("'%s': reason '%s' lacks '%s'", bad[i].rel, w, bad[i].needle);
    }
    /* a new file and an existing one to write */
    assert_int_equal(srv_path_resolve(root, "sub/new.json", 2, full, sizeof full, w, sizeof w), 0);
    assert_int_equal(srv_path_resolve(root, "b.json", 2, full, sizeof full, w, sizeof w), 0);
}

/* The checks of test_paths through the walk a kernel without openat2 takes: links are
 * refused there, even one that stays inside. */
static void
test_paths_walk(void **state) {
    (void)state;
    if (!root[0])
        fail_msg("test_paths made no root folder");
    srv_openat2_off = 1;
    char full[PATH_MAX], w[256];
    assert_int_equal(srv_path_resolve(root, "sub/a.nrrd", 0, full, sizeof full, w, sizeof w), 0);
    assert_int_equal(srv_path_resolve(root, "sub/", 1, full, sizeof full, w, sizeof w), 0);
    assert_int_equal(srv_path_resolve(root, "sub/new.json", 2, full, sizeof full, w, sizeof w), 0);
    assert_int_not_equal(srv_path_resolve(root, "sub/in", 0, full, sizeof full, w, sizeof w), 0);
    assert_non_null(strstr(w, "leaves the root"));
    assert_int_not_equal(srv_path_resolve(root, "out/passwd", 0, full, sizeof full, w, sizeof w),
                         0);
    assert_non_null(strstr(w, "leaves the root"));
    assert_int_not_equal(srv_path_resolve(root, "out", 1, full, sizeof full, w, sizeof w), 0);
    assert_int_not_equal(srv_path_resolve(root, "out/x.json", 2, full, sizeof full, w, sizeof w),
                         0);
    assert_non_null(strstr(w, "leaves the root"));
    int rfd = open(root, O_PATH | O_DIRECTORY);
    assert_true(rfd >= 0);
    errno = 0;
    assert_int_equal(srv_open_beneath(rfd, "sub/../sub/a.nrrd", O_PATH), -1);
    assert_int_equal(errno, EXDEV);
    /* the root itself and a folder, opened to be listed */
    for (int k = 0; k < 2; k++) {
        int dfd = srv_open_beneath(rfd, k ? "sub" : "", O_RDONLY | O_DIRECTORY);
        assert_true(dfd >= 0);
        DIR *d = fdopendir(dfd);
        assert_non_null(d);
        closedir(d);
    }
    srv_openat2_off = 0;
    /* openat2 itself: ".." that climbs out, an absolute link */
    errno = 0;
    assert_int_equal(srv_open_beneath(rfd, "sub/../../x", O_PATH), -1);
    assert_int_equal(errno, EXDEV);
    assert_int_equal(srv_open_beneath(rfd, "out", O_PATH), -1);
    int fd = srv_open_beneath(rfd, "sub/../sub/a.nrrd", O_RDONLY);
    assert_true(fd >= 0);
    close(fd);
    close(rfd);
}

static void
test_urls(void **state) {
    (void)state;
    static const struct {
        const char *in, *out;
    } good[] = {
        {"HTTP://Example.ORG", "http://example.org/"},
        {"http://example.org:80/a/b.zarr", "http://example.org/a/b.zarr"},
        {"https://example.org:443/a", "https://example.org/a"},
        {"https://example.org:8443/a/", "https://example.org:8443/a/"},
        {"http://127.0.0.1:9000/d%61ta/%7e/x%2a", "http://127.0.0.1:9000/data/~/x%2A"},
        {"http://[::1]:8080/x", "http://[::1]:8080/x"},
        {"s3://my-bucket/key/img.ome.zarr", "s3://my-bucket/key/img.ome.zarr"},
        {"https://h/x?X-Amz-Signature=1#frag", "https://h/x?X-Amz-Signature=1"},
    };
    char out[SRV_URL_MAX], w[512];
    for (size_t i = 0; i < sizeof good / sizeof good[0]; i++) {
        if (srv_url_normalize(good[i].in, out, sizeof out, w, sizeof w))
            fail_msg("'%s' refused: %s", good[i].in, w);
        if (strcmp(out, good[i].out))
            fail_msg("'%s' -> '%s', not '%s'", good[i].in, out, good[i].out);
    }
    static const struct {
        const char *in, *needle;
    } bad[] = {
        {"file:///etc/passwd", "only http"},
        {"gopher://h/x", "only http"},
        {"/etc/passwd", "not a URL"},
        {"http://user:pw@h/x", "user information"},
        {"http://h@evil/x", "user information"},
        {"http://h/a/../b", "'..'"},
        {"http://h/a/%2e%2E/b", "'..'"},
        {"http://h/a/./b", "'.'"},
        {"http://h/a//b", "empty"},
        {"http://h/a%2fb", "encoded"},
        {"http://h/a%5cb", "encoded"},
        {"http://h/a%00b", "encoded"},
        {"http://h/a%zz", "percent-escape"},
        {"http://h/a%2", "percent-escape"},
        {"http://h/a\\b", "backslash"},
        {"http://h/a b", "space"},
        {"http://h:99999/", "port"},
        {"http://h:0/", "port 0"},
        {"http://h:/", "port"},
        {"s3://b:9000/k", "not a port"},
        {"http://h%2f/x", "host"},
        {"http:///x", "no host"},
        {"http://[zz]/x", "IPv6"},
        {"http://h\x7f/", "control"},
    };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        w[0] = '\0';
        if (srv_url_normalize(bad[i].in, out, sizeof out, w, sizeof w) == 0)
            fail_msg("accepted '%s' as '%s'", bad[i].in, out);
        if (!strstr(w, bad[i].needle))
            fail_msg("'%s': reason '%s' lacks '%s'", bad[i].in, w, bad[i].needle);
        for (const char *p = w; *p; p++)
            assert_true((unsigned char)*p >= 0x20);
    }
    char *urls[] = {"http://h/given/a.zarr", "https://h/q?sig=1"};
    char *prefixes[] = {"http://h:8000/data", "s3://bucket/images/"};
    static const struct {
        const char *url;
        int ok;
    } allow[] = {
        {"http://h/given/a.zarr", 1},     {"http://h/given/a.zarr/", 0},
        {"http://h/given/b.zarr", 0},     {"https://h/given/a.zarr", 0},
        {"https://h/q?sig=1", 1},         {"https://h/q?sig=2", 0},
        {"http://h:8000/data", 1},        {"http://h:8000/data/x.zarr", 1},
        {"http://h:8000/database", 0},    {"http://h:8000/dat", 0},
        {"http://h:8001/data/x", 0},      {"http://h/data/x", 0},
        {"https://h:8000/data/x", 0},     {"http://h:8000/data/x?a=1", 0},
        {"s3://bucket/images/x.zarr", 1}, {"s3://bucket/images", 0},
        {"s3://bucket2/images/x", 0},
    };
    for (size_t i = 0; i < sizeof allow / sizeof allow[0]; i++)
        if (srv_url_allowed(allow[i].url, urls, 2, prefixes, 2) != allow[i].ok)
            fail_msg("'%s': allowed %d, expected %d", allow[i].url, !allow[i].ok, allow[i].ok);
    /* a client's URL is compared in normal form: these all name the prefix's folder */
    static const char *const sneaky[] = {"HTTP://H:8000/data/x", "http://h:8000/%64ata/x"};
    for (size_t i = 0; i < 2; i++) {
        assert_int_equal(srv_url_normalize(sneaky[i], out, sizeof out, w, sizeof w), 0);
        assert_int_equal(srv_url_allowed(out, urls, 2, prefixes, 2), 1);
    }
    assert_int_equal(srv_is_url("s3://b/k"), 1);
    assert_int_equal(srv_is_url("a.nrrd"), 0);
    assert_int_equal(srv_is_url("dir://x"), 1);
    assert_int_equal(srv_is_url("1x://x"), 0);
}

/* A scene's "file" entries, written into the root of test_paths. */
static void
test_scene(void **state) {
    (void)state;
    if (!root[0])
        fail_msg("test_paths made no root folder");
    static const struct {
        const char *file, *needle; /* NULL: accepted */
    } cases[] = {
        {"a.nrrd", NULL},
        {"../sub/a.nrrd", NULL},
        {"in", NULL},
        {"missing.nrrd", NULL},
        {"../../etc/passwd", "leaves the root"},
        {"../out/passwd", "leaves the root"},
        {"/etc/passwd", "outside the root"},
        {"http://h/x.zarr", "not a URL the server was given"},
        {"http://h:8000/data/x.zarr", NULL},
    };
    char *prefixes[] = {"http://h:8000/data"};
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        char p[PATH_MAX + 32], text[512];
        snprintf(p, sizeof p, "%s/sub/scene.json", root);
        int n =
            snprintf(text, sizeof text, "{\"objects\": [{\"type\": \"volume\", \"file\": \"%s\"}]}",
                     cases[i].file);
        vt_write_file(p, text, (size_t)n);
        char w[512] = "";
        int rc = srv_scene_confined(root, p, NULL, 0, prefixes, 1, w, sizeof w);
        if (!cases[i].needle && rc != 0)
            fail_msg("'%s' refused: %s", cases[i].file, w);
        if (cases[i].needle && (rc == 0 || !strstr(w, cases[i].needle) ||
                                !strstr(w, "sub/scene.json") || !strstr(w, cases[i].file)))
            fail_msg("'%s': rc %d, reason '%s'", cases[i].file, rc, w);
    }
    /* a texture's image: the same rule */
    {
        char p[PATH_MAX + 32];
        snprintf(p, sizeof p, "%s/sub/scene.json", root);
        static const char text[] = "{\"objects\": [{\"type\": \"sphere\", \"texture\": "
                                   "{\"image\": \"../../x.png\"}}]}";
        vt_write_file(p, text, sizeof text - 1);
        char w[512] = "";
        assert_int_not_equal(srv_scene_confined(root, p, NULL, 0, NULL, 0, w, sizeof w), 0);
        assert_non_null(strstr(w, "\"image\" '../../x.png' leaves the root"));
    }
    /* an absolute path inside the root is inside */
    char p[PATH_MAX + 32], text[PATH_MAX + 128];
    snprintf(p, sizeof p, "%s/sub/scene.json", root);
    int n = snprintf(text, sizeof text, "{\"objects\": [{\"file\": \"%s/sub/a.nrrd\"}]}", root);
    vt_write_file(p, text, (size_t)n);
    char w[512];
    assert_int_equal(srv_scene_confined(root, p, NULL, 0, NULL, 0, w, sizeof w), 0);
    /* a volume file is not read as a scene */
    snprintf(p, sizeof p, "%s/sub/a.nrrd", root);
    assert_int_equal(srv_scene_confined(root, p, NULL, 0, NULL, 0, w, sizeof w), 0);
}

int
main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_good),  cmocka_unit_test(test_bad),
        cmocka_unit_test(test_paths), cmocka_unit_test(test_paths_walk),
        cmocka_unit_test(test_urls),  cmocka_unit_test(test_scene),
    };
    return vt_run_tests(tests, NULL, NULL);
}

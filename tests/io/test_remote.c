/*
 * The remote byte sources (src/io/store/bytesrc_http.c, http_resp.c)
 * without a network:
 *
 * - S3 addressing: s3://BUCKET/KEY as the bucket's virtual host in the
 *   region, or path-style under AWS_ENDPOINT_URL; virtual-host and
 *   path-style amazonaws.com URLs recognised with their bucket and
 *   region; an URL under the endpoint is S3; user information never kept
 *   for messages; malformed URLs refused.
 * - Credentials: the environment's, a profile of a credentials file,
 *   anonymous with AWS_NO_SIGN_REQUEST or none.
 * - SigV4 on the wire: a one-shot loopback server records the request; a
 *   signed one carries Authorization AWS4-HMAC-SHA256 with the key id,
 *   x-amz-date, x-amz-content-sha256 and the session token, never the
 *   secret; an anonymous one no Authorization.
 * - A batch of six reads on one multi handle (one absent): each its own
 *   bytes, the absent one missing; bs_http_stats counts the six requests
 *   and at least six in flight at once.
 * - Responses: 206 with the range asked, a wrong Content-Range, 200 with the
 *   whole object to a range (sliced), a suffix, a truncated body, a
 *   Content-Length over the budget, Content-Encoding refused, 404 missing,
 *   416 past the end.
 */
#include "testutil.h"

#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <unistd.h>

#include "io/store/bytesrc.h"
#include "io/store/http_resp.h"
#include "volvis/volvis.h"

static void
test_s3_addressing(void **state) {
    (void)state;
    bs_target t;
    assert_int_equal(bs_target_parse(&t, "s3://my-bucket/a/b.zarr/", NULL, NULL), VV_OK);
    assert_true(t.s3 && !t.path_style);
    assert_string_equal(t.bucket, "my-bucket");
    assert_string_equal(t.region, "us-east-1");
    assert_string_equal(t.base, "https://my-bucket.s3.us-east-1.amazonaws.com/a/b.zarr");
    assert_string_equal(t.shown, "s3://my-bucket/a/b.zarr");
    assert_int_equal(bs_target_parse(&t, "s3://b/k", NULL, "eu-west-1"), VV_OK);
    assert_string_equal(t.base, "https://b.s3.eu-west-1.amazonaws.com/k");
    /* an endpoint: path-style */
    assert_int_equal(bs_target_parse(&t, "s3://b/k", "http://127.0.0.1:9000/", NULL), VV_OK);
    assert_true(t.s3 && t.path_style);
    assert_string_equal(t.base, "http://127.0.0.1:9000/b/k");
    /* virtual host with a region, and the legacy dash form */
    assert_int_equal(
        bs_target_parse(&t, "https://idr.s3.eu-west-2.amazonaws.com/x/y.zarr", NULL, NULL), VV_OK);
    assert_true(t.s3 && !t.path_style);
    assert_string_equal(t.bucket, "idr");
    assert_string_equal(t.region, "eu-west-2");
    assert_string_equal(t.base, "https://idr.s3.eu-west-2.amazonaws.com/x/y.zarr");
    assert_int_equal(bs_target_parse(&t, "https://bk.s3-us-west-1.amazonaws.com/z", NULL, NULL),
                     VV_OK);
    assert_true(t.s3);
    assert_string_equal(t.bucket, "bk");
    assert_string_equal(t.region, "us-west-1");
    assert_int_equal(bs_target_parse(&t, "https://bk.s3.amazonaws.com/z", NULL, NULL), VV_OK);
    assert_true(t.s3);
    assert_string_equal(t.region, "us-east-1");
    /* path-style amazonaws.com */
    assert_int_equal(
        bs_target_parse(&t, "https://s3.us-west-2.amazonaws.com/bkt/img.zarr", NULL, NULL), VV_OK);
    assert_true(t.s3 && t.path_style);
    assert_string_equal(t.bucket, "bkt");
    assert_string_equal(t.region, "us-west-2");
    /* under the endpoint: S3 path-style */
    assert_int_equal(
        bs_target_parse(&t, "http://127.0.0.1:9000/bkt/store", "http://127.0.0.1:9000", NULL),
        VV_OK);
    assert_true(t.s3 && t.path_style);
    assert_string_equal(t.bucket, "bkt");
    /* plain HTTP; user information not shown */
    assert_int_equal(
        bs_target_parse(&t, "https://user:pw@example.org/data/img.ome.zarr", NULL, NULL), VV_OK);
    assert_false(t.s3);
    assert_string_equal(t.shown, "https://example.org/data/img.ome.zarr");
    assert_null(strstr(t.base, "pw"));
    assert_int_equal(bs_target_parse(&t, "http://example.org:8080", "http://127.0.0.1:9000", NULL),
                     VV_OK);
    assert_false(t.s3);
    /* the door: a URL is the Zarr row, nothing local looked at */
    assert_true(vv_path_is_url("HTTPS://h/x") && vv_path_is_url("s3://b/k") &&
                vv_path_is_url("http://h"));
    assert_false(vv_path_is_url("/tmp/http://x") || vv_path_is_url("file:///x") ||
                 vv_path_is_url(NULL));
    assert_int_equal(vv_format_detect("http://127.0.0.1:9/none.ome.zarr"), VV_FORMAT_OME_ZARR);
    assert_int_equal(vv_format_detect("s3://b/none.zarr"), VV_FORMAT_OME_ZARR);
    /* refused */
    assert_int_equal(bs_target_parse(&t, "s3:///key", NULL, NULL), VV_ERR_INVALID);
    assert_int_equal(bs_target_parse(&t, "s3://bad bucket/key", NULL, NULL), VV_ERR_INVALID);
    assert_int_equal(bs_target_parse(&t, "ftp://x/y", NULL, NULL), VV_ERR_INVALID);
    assert_int_equal(bs_target_parse(&t, "s3://b/k", "file:///tmp", NULL), VV_ERR_INVALID);
    vv_error_clear();
}

static void
clear_aws(void) {
    const char *v[] = {"AWS_ACCESS_KEY_ID", "AWS_SECRET_ACCESS_KEY",       "AWS_SESSION_TOKEN",
                       "AWS_PROFILE",       "AWS_SHARED_CREDENTIALS_FILE", "AWS_CONFIG_FILE",
                       "AWS_REGION",        "AWS_DEFAULT_REGION",          "AWS_NO_SIGN_REQUEST",
                       "AWS_ENDPOINT_URL",  "AWS_ENDPOINT_URL_S3"};
    for (size_t i = 0; i < sizeof v / sizeof v[0]; i++)
        unsetenv(v[i]);
}

static void
test_credentials(void **state) {
    (void)state;
    clear_aws();
    char dir[1024];
    assert_non_null(vt_mkdtemp(dir, sizeof dir, "vv_remote_"));
    setenv("HOME", dir, 1);
    bs_target t;
    assert_int_equal(bs_target_parse(&t, "s3://b/k", NULL, NULL), VV_OK);
    bs_target_credentials(&t);
    assert_false(t.sign);
    setenv("AWS_ACCESS_KEY_ID", "AKIDENV", 1);
    setenv("AWS_SECRET_ACCESS_KEY", "envsecret", 1);
    setenv("AWS_SESSION_TOKEN", "tok", 1);
    bs_target_credentials(&t);
    assert_true(t.sign);
    assert_string_equal(t.key_id, "AKIDENV");
    assert_string_equal(t.token, "tok");
    assert_null(strstr(t.cred_from, "envsecret"));
    setenv("AWS_NO_SIGN_REQUEST", "YES", 1);
    bs_target_credentials(&t);
    assert_false(t.sign);
    clear_aws();
    char cred[4200], conf[4200];
    snprintf(cred, sizeof cred, "%s/credentials", dir);
    snprintf(conf, sizeof conf, "%s/config", dir);
    FILE *f = fopen(cred, "w");
    assert_non_null(f);
    fprintf(f, "[default]\naws_access_key_id = AKIDDEF\naws_secret_access_key = d\n"
               "[viewer]\n aws_access_key_id=AKIDVIEW \naws_secret_access_key = v s\n");
    fclose(f);
    f = fopen(conf, "w");
    assert_non_null(f);
    fprintf(f, "[default]\nregion = ap-south-1\n[profile viewer]\nregion = eu-central-1\n");
    fclose(f);
    setenv("AWS_SHARED_CREDENTIALS_FILE", cred, 1);
    setenv("AWS_CONFIG_FILE", conf, 1);
    bs_target_credentials(&t);
    assert_true(t.sign);
    assert_string_equal(t.key_id, "AKIDDEF");
    assert_string_equal(t.region, "ap-south-1");
    setenv("AWS_PROFILE", "viewer", 1);
    assert_int_equal(bs_target_parse(&t, "s3://b/k", NULL, NULL), VV_OK);
    bs_target_credentials(&t);
    assert_string_equal(t.key_id, "AKIDVIEW");
    assert_string_equal(t.secret, "v s");
    assert_string_equal(t.region, "eu-central-1");
    assert_string_equal(t.cred_from, "profile viewer");
    /* the URL's own region wins */
    assert_int_equal(bs_target_parse(&t, "https://b.s3.sa-east-1.amazonaws.com/k", NULL, NULL),
                     VV_OK);
    bs_target_credentials(&t);
    assert_string_equal(t.region, "sa-east-1");
    clear_aws();
    unlink(cred);
    unlink(conf);
    rmdir(dir);
}

/* ---- a one-shot loopback server recording the request ------------------ */

typedef struct one_shot {
    int fd, port;
    char req[16384];
} one_shot;

static void *
serve_once(void *u) {
    one_shot *o = u;
    const int c = accept(o->fd, NULL, NULL);
    if (c < 0)
        return NULL;
    vt_read_request_head(c, o->req, sizeof o->req);
    const char *resp = "HTTP/1.1 200 OK\r\nContent-Length: 2\r\nConnection: close\r\n\r\nok";
    ssize_t w = write(c, resp, strlen(resp));
    (void)w;
    close(c);
    return NULL;
}

static void
one_shot_start(one_shot *o, pthread_t *th) {
    memset(o, 0, sizeof *o);
    o->fd = vt_listen_loopback(4, &o->port);
    assert_int_equal(pthread_create(th, NULL, serve_once, o), 0);
}

/* A GET of key "k" of s3://BUCKET/store through the endpoint of @p o. */
static void
get_through(one_shot *o, const char *bucket) {
    pthread_t th;
    one_shot_start(o, &th);
    char ep[64], root[128];
    snprintf(ep, sizeof ep, "http://127.0.0.1:%d", o->port);
    setenv("AWS_ENDPOINT_URL", ep, 1);
    snprintf(root, sizeof root, "s3://%s/store", bucket);
    vv_bytesrc *src = bs_remote(root);
    assert_non_null(src);
    bs_get g = {.key = "k", .off = 0, .len = BS_ALL, .max = 100};
    const vv_status s = src->ops->get_many(src, &g, 1);
    assert_int_equal(s, VV_OK);
    assert_int_equal(g.n, 2);
    assert_memory_equal(g.out, "ok", 2);
    free(g.out);
    pthread_join(th, NULL);
    close(o->fd);
}

static void
test_sigv4_on_the_wire(void **state) {
    (void)state;
    clear_aws();
    setenv("AWS_ACCESS_KEY_ID", "AKIDWIRE", 1);
    setenv("AWS_SECRET_ACCESS_KEY", "topsecretvalue", 1);
    setenv("AWS_SESSION_TOKEN", "sessiontok", 1);
    setenv("AWS_REGION", "eu-west-3", 1);
    one_shot o;
    get_through(&o, "signed-bucket");
    assert_non_null(strstr(o.req, "GET /signed-bucket/store/k HTTP/1.1"));
    assert_non_null(strstr(o.req, "Authorization: AWS4-HMAC-SHA256 Credential=AKIDWIRE/"));
    assert_non_null(strstr(o.req, "/eu-west-3/s3/aws4_request"));
    assert_non_null(strstr(o.req, "SignedHeaders="));
    assert_non_null(strstr(o.req, "x-amz-date: ") ? o.req : strstr(o.req, "X-Amz-Date: "));
    assert_non_null(strstr(o.req, "x-amz-content-sha256: e3b0c442"));
    assert_non_null(strstr(o.req, "x-amz-security-token: sessiontok"));
    assert_null(strstr(o.req, "topsecretvalue"));
    assert_null(strstr(o.req, "Accept-Encoding"));
    clear_aws();
    setenv("AWS_NO_SIGN_REQUEST", "YES", 1);
    get_through(&o, "anon-bucket");
    assert_non_null(strstr(o.req, "GET /anon-bucket/store/k HTTP/1.1"));
    assert_null(strstr(o.req, "Authorization"));
    clear_aws();
}

/* ---- a batch: many ranges in flight on one multi handle ------------------ */

typedef struct echo_srv {
    int fd, port, n;
} echo_srv;

/* Answers @p n requests, one a connection: the body is the path asked. */
static void *
serve_echo(void *u) {
    echo_srv *o = u;
    for (int k = 0; k < o->n; k++) {
        const int c = accept(o->fd, NULL, NULL);
        if (c < 0)
            return NULL;
        char req[4096];
        vt_read_request_head(c, req, sizeof req);
        char path[256] = "";
        sscanf(req, "GET %255s", path);
        const int missing = strstr(path, "absent") != NULL;
        char resp[600];
        snprintf(resp, sizeof resp,
                 missing
                     ? "HTTP/1.1 404 Not Found\r\nContent-Length: 0\r\nConnection: close\r\n\r\n"
                     : "HTTP/1.1 200 OK\r\nContent-Length: %zu\r\nConnection: close\r\n\r\n%s",
                 strlen(path), path);
        ssize_t w = write(c, resp, strlen(resp));
        (void)w;
        close(c);
    }
    return NULL;
}

static void
test_batch(void **state) {
    (void)state;
    clear_aws();
    echo_srv o = {.n = 6};
    o.fd = vt_listen_loopback(16, &o.port);
    pthread_t th;
    assert_int_equal(pthread_create(&th, NULL, serve_echo, &o), 0);
    char root[64];
    snprintf(root, sizeof root, "http://127.0.0.1:%d/st", o.port);
    vv_bytesrc *src = bs_remote(root);
    assert_non_null(src);
    bs_get g[6];
    const char *keys[6] = {"a/0", "b/1", "absent", "c/2/3", "d", "e/zarr.json"};
    for (int i = 0; i < 6; i++)
        g[i] = (bs_get){.key = keys[i], .off = 0, .len = BS_ALL, .max = 100};
    uint64_t req0, req1;
    int most;
    bs_http_stats(&req0, &most);
    assert_int_equal(src->ops->get_many(src, g, 6), VV_OK);
    /* all six were handed to libcurl together: six in flight at once */
    bs_http_stats(&req1, &most);
    assert_true(req1 - req0 >= 6);
    assert_true(most >= 6);
    for (int i = 0; i < 6; i++) {
        char want[64];
        snprintf(want, sizeof want, "/st/%s", keys[i]);
        if (i == 2) {
            assert_true(g[i].missing);
            assert_null(g[i].out);
            continue;
        }
        assert_false(g[i].missing);
        assert_int_equal(g[i].n, strlen(want));
        assert_memory_equal(g[i].out, want, g[i].n);
        free(g[i].out);
    }
    pthread_join(th, NULL);
    close(o.fd);
}

/* ---- responses ------------------------------------------------------------ */

/* Feeds @p head (lines separated by \n) and @p body to @p r. */
static void
feed(http_resp *r, const char *head, const char *body, size_t n) {
    const char *p = head;
    while (*p) {
        const char *e = strchr(p, '\n');
        const size_t len = e ? (size_t)(e - p) + 1 : strlen(p);
        if (!http_resp_header(r, p, len))
            return;
        p += len;
    }
    if (!http_resp_header(r, "\r\n", 2))
        return;
    http_resp_body(r, body, n);
}

static vv_status
answer(uint64_t off, uint64_t len, uint64_t max, int ranged, const char *head, const char *body,
       size_t n, unsigned char **out, size_t *got, uint64_t *size, int *missing) {
    http_resp r;
    http_resp_init(&r, off, len, max, ranged, 0);
    feed(&r, head, body, n);
    const vv_status s = http_resp_finish(&r, out, got, size, missing);
    http_resp_free(&r);
    return s;
}

static void
test_responses(void **state) {
    (void)state;
    unsigned char *out = NULL;
    size_t n = 0;
    uint64_t size = 0;
    int missing = 0;
    /* the range asked */
    assert_int_equal(answer(2, 3, 10, 1,
                            "HTTP/1.1 206 Partial\nContent-Range: bytes 2-4/10\nContent-Length: "
                            "3\nETag: \"abc\"\n",
                            "cde", 3, &out, &n, &size, &missing),
                     VV_OK);
    assert_int_equal(n, 3);
    assert_int_equal(size, 10);
    assert_memory_equal(out, "cde", 3);
    free(out);
    /* a Content-Range off by one */
    assert_int_equal(answer(2, 3, 10, 1, "HTTP/1.1 206 Partial\nContent-Range: bytes 3-5/10\n",
                            "def", 3, &out, &n, &size, &missing),
                     VV_ERR_FORMAT);
    assert_non_null(strstr(vv_error_message(), "Content-Range"));
    /* the whole object to a range: sliced */
    assert_int_equal(answer(2, 3, 10, 1, "HTTP/2 200\ncontent-length: 10\n", "abcdefghij", 10, &out,
                            &n, &size, &missing),
                     VV_OK);
    assert_int_equal(n, 3);
    assert_memory_equal(out, "cde", 3);
    free(out);
    /* a suffix */
    assert_int_equal(answer(HTTP_SUFFIX, 4, 4, 1, "HTTP/1.1 206 OK\nContent-Range: bytes 6-9/10\n",
                            "ghij", 4, &out, &n, &size, &missing),
                     VV_OK);
    assert_int_equal(size, 10);
    assert_memory_equal(out, "ghij", 4);
    free(out);
    assert_int_equal(answer(HTTP_SUFFIX, 4, 4, 1, "HTTP/1.1 206 OK\nContent-Range: bytes 5-8/10\n",
                            "fghi", 4, &out, &n, &size, &missing),
                     VV_ERR_FORMAT);
    /* truncated */
    assert_int_equal(answer(0, HTTP_ALL, 100, 0, "HTTP/1.1 200 OK\nContent-Length: 10\n", "abc", 3,
                            &out, &n, &size, &missing),
                     VV_ERR_FORMAT);
    assert_non_null(strstr(vv_error_message(), "truncated"));
    /* over the budget, by Content-Length and by bytes */
    assert_int_equal(answer(0, HTTP_ALL, 4, 0,
                            "HTTP/1.1 200 OK\nContent-Length: 1000000000000000\n", "abc", 3, &out,
                            &n, &size, &missing),
                     VV_ERR_LIMIT);
    assert_int_equal(
        answer(0, HTTP_ALL, 4, 0, "HTTP/1.1 200 OK\n", "abcdefgh", 8, &out, &n, &size, &missing),
        VV_ERR_LIMIT);
    assert_int_equal(answer(0, 4, 4, 1, "HTTP/1.1 206 OK\nContent-Range: bytes 0-3/9\n", "abcdefgh",
                            8, &out, &n, &size, &missing),
                     VV_ERR_FORMAT);
    /* a Content-Encoding never asked for */
    assert_int_equal(answer(0, HTTP_ALL, 100, 0, "HTTP/1.1 200 OK\nContent-Encoding: gzip\n", "x",
                            1, &out, &n, &size, &missing),
                     VV_ERR_FORMAT);
    assert_non_null(strstr(vv_error_message(), "Content-Encoding"));
    /* absent; past the end */
    assert_int_equal(answer(0, HTTP_ALL, 100, 0, "HTTP/1.1 404 Not Found\n", "nope", 4, &out, &n,
                            &size, &missing),
                     VV_OK);
    assert_true(missing);
    assert_null(out);
    assert_int_equal(answer(20, 4, 4, 1, "HTTP/1.1 416 Range\nContent-Range: bytes */10\n", "", 0,
                            &out, &n, &size, &missing),
                     VV_ERR_FORMAT);
    assert_non_null(strstr(vv_error_message(), "past"));
    /* malformed headers */
    assert_int_equal(
        answer(0, HTTP_ALL, 100, 0, "HTTP/1.1 2x0 OK\n", "", 0, &out, &n, &size, &missing),
        VV_ERR_FORMAT);
    assert_int_equal(answer(0, HTTP_ALL, 100, 0, "HTTP/1.1 200 OK\nContent-Length: -1\n", "", 0,
                            &out, &n, &size, &missing),
                     VV_ERR_FORMAT);
    vv_error_clear();
}

int
main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_s3_addressing),     cmocka_unit_test(test_credentials),
        cmocka_unit_test(test_sigv4_on_the_wire), cmocka_unit_test(test_batch),
        cmocka_unit_test(test_responses),
    };
    return vt_run_tests(tests, NULL, NULL);
}

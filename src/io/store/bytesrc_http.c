/*
 * The remote byte sources (bytesrc.h): HTTP(S) and S3 through libcurl.
 *
 * One source per store URL, kept for the process's life: a curl share
 * (DNS cache, TLS sessions) and a pool of multi handles, each holding its
 * connections open between reads, so that the reads of one thread reuse
 * them and the reads of many threads run at once. A batch (get_many) puts
 * all its ranges in flight on one multi handle (VOLVIS_HTTP_MAX_IN_FLIGHT
 * at a time, HTTP/2 multiplexed where the server offers it). Each read:
 * a byte range (Range; 206 and its Content-Range checked, a 200 with the
 * whole object sliced up to HTTP_WHOLE_MAX), never more than its budget
 * received (Content-Length and the bytes heard both checked; no
 * Content-Encoding asked for and none accepted), retried with exponential
 * back-off on 5xx, 429, timeouts and dropped connections
 * (VOLVIS_HTTP_RETRIES), a connect timeout and a low-speed timeout
 * (VOLVIS_HTTP_CONNECT_TIMEOUT, VOLVIS_HTTP_LOW_SPEED_TIME and
 * VOLVIS_HTTP_LOW_SPEED_LIMIT), TLS verified (the system's CAs, or
 * CURL_CA_BUNDLE / SSL_CERT_FILE), proxies from the environment (libcurl's
 * http_proxy, https_proxy, no_proxy), redirects followed here, at most 5,
 * only to http or https, never from https down to http, never to another
 * host when signing. 404 (and 403 AccessDenied or NoSuchKey on S3) is a
 * missing object. S3: SigV4 (CURLOPT_AWS_SIGV4) with the credentials of
 * the environment or ~/.aws, or anonymous. Errors are one line, "http:
 * URL: what" or "s3: s3://BUCKET/KEY: what"; credentials never appear.
 * A read whose caller no longer wants it (bs_get.stale, asked about every
 * 50 ms) is dropped: not sent, or its request abandoned in flight.
 */
#include <ctype.h>
#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include <curl/curl.h>

#include "core/internal.h"
#include "io/store/bytesrc.h"
#include "io/store/http_resp.h"

#define MAX_REDIRECTS 5
#define POOL_MAX 64

/* ---- settings (the environment, read once) ---------------------------------------- */

static struct {
    int in_flight, retries;
    long connect_timeout, low_speed_time, low_speed_limit;
    char cache_dir[4096]; /* "" no cache on disk */
    uint64_t cache_max;
} cfg;

/* The on-disk cache of fetched bytes: its size kept under cfg.cache_max. */
static pthread_mutex_t cache_lock = PTHREAD_MUTEX_INITIALIZER;
static int cache_scanned;
static uint64_t cache_total; /* bytes of its entries: scanned once, then counted */
static pthread_once_t cfg_once = PTHREAD_ONCE_INIT;

/* The process's requests: started in all, in flight now and at most
 * (bs_http_stats; VOLVIS_HTTP_STATS=1 prints them at exit). */
static atomic_ullong stat_requests;
static atomic_int stat_now, stat_max;

static void
stats_print(void) {
    uint64_t req;
    int most;
    bs_http_stats(&req, &most);
    fprintf(stderr, "volvis: http: %llu requests, at most %d in flight\n", (unsigned long long)req,
            most);
}

void
bs_http_stats(uint64_t *requests, int *max_in_flight) {
    *requests = atomic_load(&stat_requests);
    *max_in_flight = atomic_load(&stat_max);
}

/* One more request in flight (@p d 1) or one fewer (-1). */
static void
stats_flight(int d) {
    const int now = atomic_fetch_add(&stat_now, d) + d;
    if (d > 0) {
        atomic_fetch_add(&stat_requests, 1);
        for (int m = atomic_load(&stat_max); now > m;)
            if (atomic_compare_exchange_weak(&stat_max, &m, now))
                break;
    }
}

/* The integer of environment variable @p name in [lo, hi], else @p def. */
static long
env_long(const char *name, long def, long lo, long hi) {
    const char *v = getenv(name);
    if (!v || !*v)
        return def;
    char *end = NULL;
    errno = 0;
    const long x = strtol(v, &end, 10);
    if (errno || *end || x < lo || x > hi)
        return def;
    return x;
}

static void
cfg_init(void) {
    curl_global_init(CURL_GLOBAL_DEFAULT);
    cfg.in_flight = (int)env_long("VOLVIS_HTTP_MAX_IN_FLIGHT", 32, 1, 1024);
    cfg.retries = (int)env_long("VOLVIS_HTTP_RETRIES", 3, 0, 10);
    cfg.connect_timeout = env_long("VOLVIS_HTTP_CONNECT_TIMEOUT", 10, 1, 600);
    cfg.low_speed_time = env_long("VOLVIS_HTTP_LOW_SPEED_TIME", 10, 1, 600);
    cfg.low_speed_limit = env_long("VOLVIS_HTTP_LOW_SPEED_LIMIT", 256, 1, 1L << 30);
    const char *d = getenv("VOLVIS_HTTP_CACHE_DIR");
    if (d && *d && strlen(d) < sizeof cfg.cache_dir - 64) {
        snprintf(cfg.cache_dir, sizeof cfg.cache_dir, "%s", d);
        mkdir(d, 0700);
        struct stat st;
        if (stat(d, &st) != 0 || !S_ISDIR(st.st_mode) || access(d, W_OK | X_OK) != 0)
            cfg.cache_dir[0] = '\0'; /* not usable: no cache, reads go on */
    }
    uint64_t mx = 0;
    const char *m = getenv("VOLVIS_HTTP_CACHE_MAX");
    cfg.cache_max = m && vv_memory_size_parse(m, &mx) == VV_OK && mx > 0 ? mx : (1ull << 30);
    const char *st = getenv("VOLVIS_HTTP_STATS");
    if (st && !strcmp(st, "1"))
        atexit(stats_print);
}

int
bs_http_in_flight(void) {
    pthread_once(&cfg_once, cfg_init);
    return cfg.in_flight;
}

/* ---- addresses ----------------------------------------------------------------------- */

/* @p url without user information ("user:pass@") into @p out. */
static void
strip_userinfo(const char *url, char *out, size_t cap) {
    const char *s = strstr(url, "://");
    const char *host = s ? s + 3 : url;
    const char *slash = strchr(host, '/');
    const char *at = strchr(host, '@');
    if (at && (!slash || at < slash))
        snprintf(out, cap, "%.*s%s", (int)(host - url), url, at + 1);
    else
        snprintf(out, cap, "%s", url);
}

/* @p s without trailing slashes. */
static void
trim_slashes(char *s) {
    size_t n = strlen(s);
    while (n > 0 && s[n - 1] == '/')
        s[--n] = '\0';
}

/* The host (and port) of http(s) URL @p url into @p host; the path after it into *path. */
static int
split_url(const char *url, char *host, size_t cap, const char **path, int *https) {
    *https = !strncasecmp(url, "https://", 8);
    if (!*https && strncasecmp(url, "http://", 7))
        return 0;
    const char *h = url + (*https ? 8 : 7);
    const char *slash = strchr(h, '/');
    const size_t n = slash ? (size_t)(slash - h) : strlen(h);
    if (n == 0 || n >= cap)
        return 0;
    memcpy(host, h, n);
    host[n] = '\0';
    for (size_t i = 0; i < n; i++)
        host[i] = (char)tolower((unsigned char)host[i]);
    *path = slash ? slash : "";
    return 1;
}

/* 1 when @p s ends with @p suf. */
static int
ends_with(const char *s, const char *suf) {
    const size_t n = strlen(s), m = strlen(suf);
    return n >= m && !strcmp(s + n - m, suf);
}

vv_status
bs_target_parse(bs_target *t, const char *url, const char *endpoint, const char *region) {
    memset(t, 0, sizeof *t);
    char clean[4096], gs[4096];
    url = bs_url_unprefix(url);
    if (strlen(url) >= sizeof clean - 1)
        return vv_error_set(VV_ERR_LIMIT, "URL too long (%zu bytes)", strlen(url));
    if (!strncasecmp(url, "gs://", 5)) { /* a public bucket, anonymously */
        const char *emu = getenv("STORAGE_EMULATOR_HOST");
        char host[1024];
        snprintf(host, sizeof host, "%s", emu && *emu ? emu : "https://storage.googleapis.com");
        trim_slashes(host);
        if (strncasecmp(host, "http://", 7) && strncasecmp(host, "https://", 8))
            return vv_error_set(VV_ERR_INVALID,
                                "STORAGE_EMULATOR_HOST \"%.200s\" is not an http(s) URL", host);
        if (url[5] == '\0' || url[5] == '/')
            return vv_error_set(VV_ERR_INVALID, "%.300s: no bucket", url);
        if (snprintf(gs, sizeof gs, "%s/%s", host, url + 5) >= (int)sizeof gs - 1)
            return vv_error_set(VV_ERR_LIMIT, "URL too long (%zu bytes)", strlen(url));
        url = gs;
    }
    strip_userinfo(url, clean, sizeof clean);
    trim_slashes(clean);
    snprintf(t->shown, sizeof t->shown, "%s", clean);
    snprintf(t->region, sizeof t->region, "%s", region && *region ? region : "");
    char ep[1024] = "";
    if (endpoint && *endpoint) {
        snprintf(ep, sizeof ep, "%s", endpoint);
        trim_slashes(ep);
        char h[512];
        const char *p;
        int https;
        if (!split_url(ep, h, sizeof h, &p, &https))
            return vv_error_set(VV_ERR_INVALID, "AWS_ENDPOINT_URL \"%.200s\" is not an http(s) URL",
                                endpoint);
    }
    if (!strncasecmp(clean, "s3://", 5)) {
        const char *b = clean + 5;
        const char *slash = strchr(b, '/');
        const size_t bn = slash ? (size_t)(slash - b) : strlen(b);
        if (bn == 0 || bn >= sizeof t->bucket)
            return vv_error_set(VV_ERR_INVALID, "%s: no bucket", clean);
        memcpy(t->bucket, b, bn);
        t->bucket[bn] = '\0';
        for (size_t i = 0; i < bn; i++)
            if (!isalnum((unsigned char)t->bucket[i]) && !strchr(".-_", t->bucket[i]))
                return vv_error_set(VV_ERR_INVALID, "%s: bucket \"%s\" is not a bucket name", clean,
                                    t->bucket);
        const char *key = slash ? slash : "";
        t->s3 = 1;
        if (!t->region[0])
            snprintf(t->region, sizeof t->region, "us-east-1");
        if (ep[0]) {
            t->path_style = 1;
            snprintf(t->base, sizeof t->base, "%s/%s%s", ep, t->bucket, key);
        } else {
            snprintf(t->base, sizeof t->base, "https://%s.s3.%s.amazonaws.com%s", t->bucket,
                     t->region, key);
        }
        trim_slashes(t->base);
        return VV_OK;
    }
    char host[512];
    const char *path;
    int https;
    if (!split_url(clean, host, sizeof host, &path, &https))
        return vv_error_set(VV_ERR_INVALID, "%s: not an http, https or s3 URL", clean);
    snprintf(t->base, sizeof t->base, "%s", clean);
    /* under the S3 endpoint: path-style */
    if (ep[0] && !strncasecmp(clean, ep, strlen(ep)) &&
        (clean[strlen(ep)] == '/' || clean[strlen(ep)] == '\0')) {
        const char *b = clean + strlen(ep);
        b += *b == '/';
        const char *slash = strchr(b, '/');
        const size_t bn = slash ? (size_t)(slash - b) : strlen(b);
        if (bn > 0 && bn < sizeof t->bucket) {
            memcpy(t->bucket, b, bn);
            t->bucket[bn] = '\0';
            t->s3 = t->path_style = 1;
        }
    } else if (ends_with(host, ".amazonaws.com")) {
        /* BUCKET.s3.REGION.amazonaws.com, BUCKET.s3-REGION..., BUCKET.s3.amazonaws.com;
         * s3.REGION.amazonaws.com/BUCKET, s3.amazonaws.com/BUCKET */
        char *s3 = strstr(host, "s3.");
        char *s3d = strstr(host, "s3-");
        char *at = s3 && (!s3d || s3 < s3d) ? s3 : s3d;
        if (at && (at == host || at[-1] == '.')) {
            char reg[64] = "";
            const char *r = at + 3;
            const char *dot = strchr(r, '.');
            if (dot && strcmp(r, "amazonaws.com") && strncmp(r, "dualstack.", 10))
                snprintf(reg, sizeof reg, "%.*s", (int)(dot - r), r);
            if (at == host) { /* path-style */
                const char *b = path + (*path == '/');
                const char *slash = strchr(b, '/');
                const size_t bn = slash ? (size_t)(slash - b) : strlen(b);
                if (bn > 0 && bn < sizeof t->bucket) {
                    memcpy(t->bucket, b, bn);
                    t->bucket[bn] = '\0';
                    t->s3 = t->path_style = 1;
                }
            } else if ((size_t)(at - 1 - host) < sizeof t->bucket) {
                memcpy(t->bucket, host, (size_t)(at - 1 - host));
                t->bucket[at - 1 - host] = '\0';
                t->s3 = 1;
            }
            if (t->s3 && reg[0])
                snprintf(t->region, sizeof t->region, "%s", reg);
        }
    }
    if (t->s3 && !t->region[0])
        snprintf(t->region, sizeof t->region, "us-east-1");
    return VV_OK;
}

/* The value of @p key in section @p section of INI file @p file into @p out. */
static int
ini_get(const char *file, const char *section, const char *key, char *out, size_t cap) {
    FILE *f = fopen(file, "r");
    if (!f)
        return 0;
    char line[4096];
    int in = 0, found = 0;
    while (!found && fgets(line, sizeof line, f)) {
        char *p = line;
        while (isspace((unsigned char)*p))
            p++;
        size_t n = strlen(p);
        while (n && isspace((unsigned char)p[n - 1]))
            p[--n] = '\0';
        if (*p == '[') {
            char *e = strchr(p, ']');
            if (e)
                *e = '\0';
            char *name = p + 1;
            while (isspace((unsigned char)*name))
                name++;
            in = !strcmp(name, section);
            continue;
        }
        if (!in || *p == '#' || *p == ';')
            continue;
        char *eq = strchr(p, '=');
        if (!eq)
            continue;
        char *k = p, *ke = eq;
        while (ke > k && isspace((unsigned char)ke[-1]))
            ke--;
        *ke = '\0';
        char *v = eq + 1;
        while (isspace((unsigned char)*v))
            v++;
        if (!strcmp(k, key)) {
            snprintf(out, cap, "%s", v);
            found = 1;
        }
    }
    fclose(f);
    return found;
}

/* The AWS file @p env (else ~/.aws/@p name) into @p out. */
static void
aws_file(const char *env, const char *name, char *out, size_t cap) {
    const char *e = getenv(env);
    const char *home = getenv("HOME");
    if (e && *e)
        snprintf(out, cap, "%s", e);
    else
        snprintf(out, cap, "%s/.aws/%s", home ? home : "", name);
}

void
bs_target_credentials(bs_target *t) {
    t->sign = 0;
    t->key_id[0] = t->secret[0] = t->token[0] = '\0';
    snprintf(t->cred_from, sizeof t->cred_from, "anonymous");
    const char *profile = getenv("AWS_PROFILE");
    if (!profile || !*profile)
        profile = "default";
    char creds[4096], conf[4096], section[300];
    aws_file("AWS_SHARED_CREDENTIALS_FILE", "credentials", creds, sizeof creds);
    aws_file("AWS_CONFIG_FILE", "config", conf, sizeof conf);
    snprintf(section, sizeof section, "%s%s", strcmp(profile, "default") ? "profile " : "",
             profile);
    /* the region the URL does not say: the environment's, else the profile's */
    if (!strcmp(t->region, "us-east-1") || !t->region[0]) {
        const char *r = getenv("AWS_REGION");
        if (!r || !*r)
            r = getenv("AWS_DEFAULT_REGION");
        char reg[64];
        if (r && *r)
            snprintf(t->region, sizeof t->region, "%s", r);
        else if (ini_get(conf, section, "region", reg, sizeof reg))
            snprintf(t->region, sizeof t->region, "%s", reg);
    }
    const char *nosign = getenv("AWS_NO_SIGN_REQUEST");
    if (nosign &&
        (!strcasecmp(nosign, "yes") || !strcasecmp(nosign, "true") || !strcmp(nosign, "1")))
        return;
    const char *id = getenv("AWS_ACCESS_KEY_ID"), *sec = getenv("AWS_SECRET_ACCESS_KEY");
    if (id && *id && sec && *sec) {
        snprintf(t->key_id, sizeof t->key_id, "%s", id);
        snprintf(t->secret, sizeof t->secret, "%s", sec);
        const char *tok = getenv("AWS_SESSION_TOKEN");
        snprintf(t->token, sizeof t->token, "%s", tok ? tok : "");
        snprintf(t->cred_from, sizeof t->cred_from, "the environment (AWS_ACCESS_KEY_ID)");
        t->sign = 1;
        return;
    }
    if ((ini_get(creds, profile, "aws_access_key_id", t->key_id, sizeof t->key_id) &&
         ini_get(creds, profile, "aws_secret_access_key", t->secret, sizeof t->secret)) ||
        (ini_get(conf, section, "aws_access_key_id", t->key_id, sizeof t->key_id) &&
         ini_get(conf, section, "aws_secret_access_key", t->secret, sizeof t->secret))) {
        if (!ini_get(creds, profile, "aws_session_token", t->token, sizeof t->token))
            ini_get(conf, section, "aws_session_token", t->token, sizeof t->token);
        snprintf(t->cred_from, sizeof t->cred_from, "profile %.100s", profile);
        t->sign = 1;
        return;
    }
    t->key_id[0] = t->secret[0] = '\0';
}

/* ---- the source ------------------------------------------------------------------------ */

typedef struct bs_http {
    vv_bytesrc base;
    char root[4096]; /* the URL as given: the registry's key */
    bs_target t;
    CURLSH *share;
    pthread_mutex_t share_lock[CURL_LOCK_DATA_LAST];
    pthread_mutex_t pool_lock;
    CURLM *pool[POOL_MAX];
    int npool;
    struct bs_http *next;
} bs_http;

static pthread_mutex_t registry_lock = PTHREAD_MUTEX_INITIALIZER;
static bs_http *registry;

static void
share_lock(CURL *h, curl_lock_data d, curl_lock_access a, void *u) {
    (void)h;
    (void)a;
    bs_http *s = u;
    if ((int)d >= 0 && (int)d < CURL_LOCK_DATA_LAST)
        pthread_mutex_lock(&s->share_lock[d]);
}

static void
share_unlock(CURL *h, curl_lock_data d, void *u) {
    (void)h;
    bs_http *s = u;
    if ((int)d >= 0 && (int)d < CURL_LOCK_DATA_LAST)
        pthread_mutex_unlock(&s->share_lock[d]);
}

/* A multi handle of @p s's pool (its connections kept open), or a new one. */
static CURLM *
pool_take(bs_http *s) {
    pthread_mutex_lock(&s->pool_lock);
    CURLM *m = s->npool ? s->pool[--s->npool] : NULL;
    pthread_mutex_unlock(&s->pool_lock);
    if (!m && (m = curl_multi_init())) {
        curl_multi_setopt(m, CURLMOPT_PIPELINING, (long)CURLPIPE_MULTIPLEX);
        curl_multi_setopt(m, CURLMOPT_MAX_HOST_CONNECTIONS, (long)cfg.in_flight);
        curl_multi_setopt(m, CURLMOPT_MAX_TOTAL_CONNECTIONS, (long)cfg.in_flight);
    }
    return m;
}

static void
pool_give(bs_http *s, CURLM *m) {
    pthread_mutex_lock(&s->pool_lock);
    if (s->npool < POOL_MAX) {
        s->pool[s->npool++] = m;
        m = NULL;
    }
    pthread_mutex_unlock(&s->pool_lock);
    if (m)
        curl_multi_cleanup(m);
}

/* One transfer of a batch. */
typedef struct xfer {
    bs_get *g;
    char url[8400];
    int redirects, tries, started, done;
    double retry_at;
    CURL *e;
    struct curl_slist *hdrs;
    http_resp r;
    char errbuf[CURL_ERROR_SIZE];
    vv_status status;
    char msg[3200];
    /* the on-disk cache: the entry's file and ETag when one is held */
    char cache_file[4200], cache_key[8500], cache_etag[128];
    int cached;
    bs_count cnt; /* its share of vv_remote_stats */
} xfer;

static double
now_s(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* ---- the on-disk cache ----------------------------------------------------------------- */

/* FNV-1a (64 bits) of @p s. */
static uint64_t
fnv1a(const char *s) {
    uint64_t h = 1469598103934665603ull;
    for (; *s; s++)
        h = (h ^ (unsigned char)*s) * 1099511628211ull;
    return h;
}

/* @p x's entry: its key (the URL asked and the range) and file; its ETag
 * when the cache holds it (x->cached). */
static void
cache_lookup(xfer *x) {
    x->cached = 0;
    if (!cfg.cache_dir[0] || x->g->len == 0)
        return;
    snprintf(x->cache_key, sizeof x->cache_key, "%s\n%llu %llu", x->url,
             (unsigned long long)x->g->off, (unsigned long long)x->g->len);
    snprintf(x->cache_file, sizeof x->cache_file, "%s/%016llx.vvhc", cfg.cache_dir,
             (unsigned long long)fnv1a(x->cache_key));
    FILE *f = fopen(x->cache_file, "rb");
    if (!f)
        return;
    char head[9000];
    const size_t n = fread(head, 1, sizeof head - 1, f);
    fclose(f);
    head[n] = '\0';
    const size_t kn = strlen(x->cache_key);
    if (strncmp(head, "VVHC1\n", 6) || strncmp(head + 6, x->cache_key, kn) || head[6 + kn] != '\n')
        return; /* another key of the same hash, or not an entry */
    const char *e = head + 6 + kn + 1, *nl = strchr(e, '\n');
    if (!nl || nl == e || (size_t)(nl - e) >= sizeof x->cache_etag)
        return;
    memcpy(x->cache_etag, e, (size_t)(nl - e));
    x->cache_etag[nl - e] = '\0';
    x->cached = 1;
}

/* The body of @p x's entry into its get (the server said 304); 0 when the
 * entry is gone or not what was asked. */
static int
cache_load(xfer *x) {
    FILE *f = fopen(x->cache_file, "rb");
    if (!f)
        return 0;
    char line[8600];
    unsigned long long size = 0;
    int ok = fgets(line, sizeof line, f) && !strcmp(line, "VVHC1\n");
    for (int i = 0; ok && i < 3; i++) /* the key's two lines, the ETag */
        ok = fgets(line, sizeof line, f) != NULL;
    ok = ok && fscanf(f, "%llu", &size) == 1 && fgetc(f) == '\n';
    const long at = ok ? ftell(f) : -1;
    struct stat st;
    ok = ok && at > 0 && fstat(fileno(f), &st) == 0 && st.st_size >= at;
    const uint64_t n = ok ? (uint64_t)(st.st_size - at) : 0;
    bs_get *g = x->g;
    ok = ok && n <= g->max && (g->len == BS_ALL || n == g->len);
    unsigned char *b = ok ? malloc(n ? (size_t)n : 1) : NULL;
    ok = b && fread(b, 1, (size_t)n, f) == n;
    fclose(f);
    if (!ok) {
        free(b);
        return 0;
    }
    g->out = b;
    g->n = (size_t)n;
    g->size = size;
    utimensat(AT_FDCWD, x->cache_file, NULL, 0); /* used: the last to go */
    return 1;
}

/* The cache's entries counted (cache_total) and, when over its bound, the
 * oldest removed until it holds at most 90 % of it (cache_lock held). */
static void
cache_evict(void) {
    DIR *d = opendir(cfg.cache_dir);
    if (!d)
        return;
    typedef struct {
        time_t t;
        uint64_t n;
        char name[64];
    } ent;
    ent *v = NULL;
    size_t k = 0, cap = 0;
    uint64_t total = 0;
    struct dirent *e;
    while ((e = readdir(d))) {
        const size_t ln = strlen(e->d_name);
        if (ln < 6 || ln >= 64 || strcmp(e->d_name + ln - 5, ".vvhc"))
            continue;
        char p[4200];
        struct stat st;
        if (snprintf(p, sizeof p, "%s/%s", cfg.cache_dir, e->d_name) >= (int)sizeof p ||
            stat(p, &st) != 0)
            continue;
        if (k == cap) {
            cap = cap ? cap * 2 : 256;
            ent *w = realloc(v, cap * sizeof *v);
            if (!w)
                break;
            v = w;
        }
        v[k].t = st.st_mtime;
        v[k].n = (uint64_t)st.st_size;
        memcpy(v[k].name, e->d_name, ln + 1); /* ln < 64: checked above */
        total += v[k++].n;
    }
    closedir(d);
    /* over the bound: the oldest go, down to 90 % of it */
    const int over = total > cfg.cache_max;
    while (over && total > cfg.cache_max / 10 * 9 && k > 0) {
        size_t old = 0;
        for (size_t i = 1; i < k; i++)
            if (v[i].t < v[old].t)
                old = i;
        char p[4200];
        snprintf(p, sizeof p, "%s/%s", cfg.cache_dir, v[old].name);
        if (unlink(p) == 0 || errno == ENOENT)
            total -= v[old].n;
        v[old] = v[--k];
    }
    free(v);
    cache_total = total;
    cache_scanned = 1;
}

/* @p x's bytes (its get's) kept with ETag @p etag, written whole then
 * renamed into place; the cache kept under its bound. */
static void
cache_store(xfer *x, const char *etag) {
    const bs_get *g = x->g;
    if (!cfg.cache_dir[0] || !etag[0] || !x->cache_file[0] || g->len == 0 || !g->out ||
        (uint64_t)g->n > cfg.cache_max / 4)
        return;
    static atomic_uint seq;
    char tmp[4300];
    snprintf(tmp, sizeof tmp, "%s/.tmp.%ld.%u", cfg.cache_dir, (long)getpid(),
             atomic_fetch_add(&seq, 1));
    FILE *f = fopen(tmp, "wb");
    if (!f)
        return;
    const int hn = fprintf(f, "VVHC1\n%s\n%s\n%llu\n", x->cache_key, etag,
                           (unsigned long long)(g->size == UINT64_MAX ? 0 : g->size));
    int ok = hn > 0 && fwrite(g->out, 1, g->n, f) == g->n;
    ok = fclose(f) == 0 && ok;
    if (!ok || rename(tmp, x->cache_file) != 0) {
        unlink(tmp);
        return;
    }
    pthread_mutex_lock(&cache_lock);
    cache_total += (uint64_t)g->n + (uint64_t)hn;
    if (!cache_scanned || cache_total > cfg.cache_max)
        cache_evict(); /* counts what is there (other processes' too), removes the oldest */
    pthread_mutex_unlock(&cache_lock);
}

static size_t
on_header(char *p, size_t size, size_t n, void *u) {
    xfer *x = u;
    return http_resp_header(&x->r, p, size * n) ? size * n : 0;
}

static size_t
on_body(char *p, size_t size, size_t n, void *u) {
    xfer *x = u;
    curl_off_t cl = -1;
    if (!x->cnt.sized && curl_easy_getinfo(x->e, CURLINFO_CONTENT_LENGTH_DOWNLOAD_T, &cl) == 0 &&
        cl > 0)
        bs_count_length(&x->cnt, (uint64_t)cl);
    bs_count_body(&x->cnt, (uint64_t)(size * n));
    return http_resp_body(&x->r, p, size * n) ? size * n : 0;
}

/* The message's name of @p x's object: the URL as the user wrote it (s3://). */
static void
shown_name(const bs_http *s, const xfer *x, char *out, size_t cap) {
    snprintf(out, cap, "%s/%s", s->t.shown, x->g->key);
}

/* @p x failed for good: its one line. */
static void
fail(const bs_http *s, xfer *x, vv_status st, const char *what) {
    char name[4400];
    shown_name(s, x, name, sizeof name);
    x->status = st;
    if (s->t.s3)
        snprintf(x->msg, sizeof x->msg, "s3: %.2000s: %.1000s", name, what);
    else
        snprintf(x->msg, sizeof x->msg, "http: %.2000s: %.1000s", name, what);
    x->done = 1;
}

/* The easy handle of @p x's next try, added to @p m. */
static int
start(bs_http *s, CURLM *m, xfer *x) {
    http_resp_reset(&x->r);
    x->errbuf[0] = '\0';
    CURL *e = x->e ? x->e : curl_easy_init();
    if (!e) {
        fail(s, x, VV_ERR_NOMEM, "out of memory for a transfer");
        return 0;
    }
    curl_easy_reset(e);
    x->e = e;
    const bs_get *g = x->g;
    curl_easy_setopt(e, CURLOPT_URL, x->url);
    curl_easy_setopt(e, CURLOPT_SHARE, s->share);
    curl_easy_setopt(e, CURLOPT_PRIVATE, x);
    curl_easy_setopt(e, CURLOPT_NOSIGNAL, 1L);
    curl_easy_setopt(e, CURLOPT_PROTOCOLS_STR, "http,https");
    curl_easy_setopt(e, CURLOPT_FOLLOWLOCATION, 0L); /* followed here, each checked */
    curl_easy_setopt(e, CURLOPT_HTTP_VERSION, (long)CURL_HTTP_VERSION_2TLS);
    /* wait for a connection that may multiplex only where one can: HTTP/2 is
     * asked over TLS alone, and over plain HTTP a batch would otherwise wait
     * for its first response before opening its other connections */
    curl_easy_setopt(e, CURLOPT_PIPEWAIT, strncmp(x->url, "https://", 8) ? 0L : 1L);
    curl_easy_setopt(e, CURLOPT_CONNECTTIMEOUT, cfg.connect_timeout);
    curl_easy_setopt(e, CURLOPT_LOW_SPEED_LIMIT, cfg.low_speed_limit);
    curl_easy_setopt(e, CURLOPT_LOW_SPEED_TIME, cfg.low_speed_time);
    curl_easy_setopt(e, CURLOPT_SSL_VERIFYPEER, 1L);
    curl_easy_setopt(e, CURLOPT_SSL_VERIFYHOST, 2L);
    const char *ca = getenv("CURL_CA_BUNDLE");
    if (!ca || !*ca)
        ca = getenv("SSL_CERT_FILE");
    if (ca && *ca)
        curl_easy_setopt(e, CURLOPT_CAINFO, ca);
    curl_easy_setopt(e, CURLOPT_USERAGENT, "volvis");
    curl_easy_setopt(e, CURLOPT_HEADERFUNCTION, on_header);
    curl_easy_setopt(e, CURLOPT_HEADERDATA, x);
    curl_easy_setopt(e, CURLOPT_WRITEFUNCTION, on_body);
    curl_easy_setopt(e, CURLOPT_WRITEDATA, x);
    curl_easy_setopt(e, CURLOPT_ERRORBUFFER, x->errbuf);
    /* what is asked: a HEAD (len 0), the whole object, or a range */
    const int head = g->len == 0;
    const int ranged = !head && !(g->off == 0 && g->len == BS_ALL);
    char range[64];
    if (head)
        curl_easy_setopt(e, CURLOPT_NOBODY, 1L);
    else if (g->off == BS_SUFFIX)
        snprintf(range, sizeof range, "-%llu", (unsigned long long)g->len);
    else if (g->len == BS_ALL)
        snprintf(range, sizeof range, "%llu-", (unsigned long long)g->off);
    else
        snprintf(range, sizeof range, "%llu-%llu", (unsigned long long)g->off,
                 (unsigned long long)(g->off + g->len - 1));
    if (ranged)
        curl_easy_setopt(e, CURLOPT_RANGE, range);
    http_resp_init(&x->r, g->off, g->len, g->max, ranged, head);
    /* a server that ignores ranges: its whole objects, all requests in
     * flight together, within a quarter of the memory budget */
    const uint64_t share = vv_memory_budget_get() / 4 / (uint64_t)cfg.in_flight;
    const uint64_t floor_ = (uint64_t)1 << 20;
    x->r.whole_max = share < floor_ ? floor_ : share > HTTP_WHOLE_MAX ? HTTP_WHOLE_MAX : share;
    curl_slist_free_all(x->hdrs);
    x->hdrs = NULL;
    if (x->cached) { /* the cache's copy, if the server says it is still the object */
        char h[200];
        snprintf(h, sizeof h, "If-None-Match: %s", x->cache_etag);
        x->hdrs = curl_slist_append(x->hdrs, h);
    }
    if (s->t.sign) {
        char sig[128];
        snprintf(sig, sizeof sig, "aws:amz:%s:s3", s->t.region);
        curl_easy_setopt(e, CURLOPT_AWS_SIGV4, sig);
        curl_easy_setopt(e, CURLOPT_USERNAME, s->t.key_id);
        curl_easy_setopt(e, CURLOPT_PASSWORD, s->t.secret);
        /* the SHA-256 of the empty payload of a GET */
        x->hdrs = curl_slist_append(x->hdrs, "x-amz-content-sha256: "
                                             "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495"
                                             "991b7852b855");
        if (s->t.token[0]) {
            char h[4200];
            snprintf(h, sizeof h, "x-amz-security-token: %s", s->t.token);
            x->hdrs = curl_slist_append(x->hdrs, h);
        }
    }
    if (x->hdrs)
        curl_easy_setopt(e, CURLOPT_HTTPHEADER, x->hdrs);
    x->started = 1;
    if (curl_multi_add_handle(m, e) != CURLM_OK) {
        fail(s, x, VV_ERR_IO, "cannot start the transfer");
        return 0;
    }
    bs_count_try(&x->cnt);
    stats_flight(1);
    return 1;
}

/* The back-off before try @p tries + 1: 0.2 s doubling, at most 5 s. */
static double
backoff(int tries) {
    double d = 0.2;
    for (int i = 1; i < tries && d < 5; i++)
        d *= 2;
    return d > 5 ? 5 : d;
}

/* A redirect of @p x to @p to checked and taken; 0 (x failed) when refused. */
static int
redirect(const bs_http *s, xfer *x, const char *to) {
    char what[600];
    const int from_https = !strncasecmp(x->url, "https://", 8);
    if (++x->redirects > MAX_REDIRECTS) {
        snprintf(what, sizeof what, "more than %d redirects (a loop?)", MAX_REDIRECTS);
        fail(s, x, VV_ERR_IO, what);
        return 0;
    }
    char host[512], host0[512];
    const char *p;
    int https, https0;
    if (!to || !split_url(to, host, sizeof host, &p, &https)) {
        snprintf(what, sizeof what, "a redirect to \"%.200s\" refused (only http and https)",
                 to ? to : "");
        fail(s, x, VV_ERR_IO, what);
        return 0;
    }
    if (from_https && !https) {
        snprintf(what, sizeof what, "a redirect from https down to http (%.200s) refused", to);
        fail(s, x, VV_ERR_IO, what);
        return 0;
    }
    if (s->t.sign && split_url(x->url, host0, sizeof host0, &p, &https0) && strcmp(host, host0)) {
        snprintf(what, sizeof what,
                 "a redirect to another host (%.200s) refused: the request is signed", host);
        fail(s, x, VV_ERR_IO, what);
        return 0;
    }
    if (strlen(to) >= sizeof x->url) {
        fail(s, x, VV_ERR_LIMIT, "a redirect to a URL too long");
        return 0;
    }
    snprintf(x->url, sizeof x->url, "%s", to);
    return 1;
}

/* 1 when curl's @p rc is worth another try. */
static int
transient(CURLcode rc) {
    switch (rc) {
    case CURLE_OPERATION_TIMEDOUT:
    case CURLE_COULDNT_CONNECT:
    case CURLE_RECV_ERROR:
    case CURLE_SEND_ERROR:
    case CURLE_PARTIAL_FILE:
    case CURLE_GOT_NOTHING:
    case CURLE_HTTP2:
    case CURLE_HTTP2_STREAM:
    case CURLE_SSL_CONNECT_ERROR:
        return 1;
    default:
        return 0;
    }
}

/* @p x's transfer ended with @p rc: done, retried later, or redirected now. */
static void
finish(bs_http *s, CURLM *m, xfer *x, CURLcode rc) {
    curl_multi_remove_handle(m, x->e);
    stats_flight(-1);
    long code = 0;
    curl_easy_getinfo(x->e, CURLINFO_RESPONSE_CODE, &code);
    char what[800];
    int retry = 0;
    if (rc == CURLE_OK && code == 304 && x->cached) {
        if (cache_load(x)) {
            x->status = VV_OK;
            x->done = 1;
        } else { /* the entry went: ask again without it */
            x->cached = 0;
            start(s, m, x);
        }
        return;
    }
    if (rc == CURLE_OK &&
        (code == 301 || code == 302 || code == 303 || code == 307 || code == 308)) {
        char *to = NULL;
        curl_easy_getinfo(x->e, CURLINFO_REDIRECT_URL, &to);
        if (redirect(s, x, to))
            start(s, m, x);
        return;
    }
    if (rc == CURLE_OK && (code >= 500 || code == 429 || code == 408)) {
        snprintf(what, sizeof what, "HTTP %ld", code);
        retry = 1;
    } else if (rc == CURLE_OK && code == 403 && s->t.s3) {
        char c[64];
        http_resp_s3_code(&x->r, c, sizeof c);
        if (!strcmp(c, "AccessDenied") || !strcmp(c, "NoSuchKey") || !c[0]) {
            /* S3 answers 403 for an absent key the caller may not list */
            x->g->missing = 1;
            x->status = VV_OK;
            x->done = 1;
            return;
        }
        snprintf(what, sizeof what, "bucket %s: HTTP 403 %s (credentials: %s)", s->t.bucket, c,
                 s->t.cred_from);
        fail(s, x, VV_ERR_IO, what);
        return;
    } else if (rc == CURLE_OK && code >= 300 && code != 404 && code != 416) {
        char c[64] = "";
        if (s->t.s3)
            http_resp_s3_code(&x->r, c, sizeof c);
        if (s->t.s3)
            snprintf(what, sizeof what, "bucket %s: HTTP %ld%s%s", s->t.bucket, code,
                     c[0] ? " " : "", c);
        else
            snprintf(what, sizeof what, "HTTP %ld", code);
        fail(s, x, VV_ERR_IO, what);
        return;
    } else if (rc == CURLE_OK) {
        bs_get *g = x->g;
        vv_status st = http_resp_finish(&x->r, &g->out, &g->n, &g->size, &g->missing);
        if (st != VV_OK) {
            snprintf(what, sizeof what, "%s", vv_error_message());
            vv_error_clear();
            /* a body shorter than announced: the connection dropped, try again */
            if (!strncmp(what, "truncated", 9))
                retry = 1;
            else {
                fail(s, x, st, what);
                return;
            }
        } else {
            if (!g->missing)
                cache_store(x, x->r.etag);
            x->status = VV_OK;
            x->done = 1;
            return;
        }
    } else if ((rc == CURLE_WRITE_ERROR || rc == CURLE_ABORTED_BY_CALLBACK) && x->r.why[0]) {
        fail(s, x, x->r.why_status, x->r.why);
        return;
    } else {
        snprintf(what, sizeof what, "%s", x->errbuf[0] ? x->errbuf : curl_easy_strerror(rc));
        if (!transient(rc)) {
            fail(s, x, VV_ERR_IO, what);
            return;
        }
        retry = 1;
    }
    if (retry && x->tries < cfg.retries) {
        x->tries++;
        x->started = 0;
        x->retry_at = now_s() + backoff(x->tries);
        return;
    }
    char w2[900];
    snprintf(w2, sizeof w2, "%s (after %d tries)", what, x->tries + 1);
    fail(s, x, VV_ERR_IO, w2);
}

/* @p x dropped because nobody wants it any more (bs_get.stale): its
 * request, when one is in flight, abandoned (libcurl closes its
 * connection), a retry waiting not made; returns 1 when a request was in
 * flight. */
static int
drop(CURLM *m, xfer *x) {
    const int active = x->started && !x->done;
    if (active) {
        curl_multi_remove_handle(m, x->e);
        stats_flight(-1);
        bs_count_landed();
    }
    x->started = 0;
    x->done = 1;
    x->status = VV_OK;
    x->g->cancelled = 1;
    bs_count_cancel(&x->cnt);
    return active;
}

/* @p key made a URL path (unreserved bytes and '/' kept, the rest %XX). */
static int
escape_key(const char *key, char *out, size_t cap) {
    size_t k = 0;
    for (const unsigned char *p = (const unsigned char *)key; *p; p++) {
        if (k + 4 >= cap)
            return 0;
        if (isalnum(*p) || strchr("-._~/", *p))
            out[k++] = (char)*p;
        else
            k += (size_t)snprintf(out + k, cap - k, "%%%02X", *p);
    }
    out[k] = '\0';
    return 1;
}

static vv_status
http_get_many(vv_bytesrc *src, bs_get *g, int n) {
    bs_http *s = (bs_http *)src;
    if (n <= 0)
        return VV_OK;
    xfer *x = calloc((size_t)n, sizeof *x);
    CURLM *m = x ? pool_take(s) : NULL;
    if (!m) {
        free(x);
        return vv_error_set(VV_ERR_NOMEM, "out of memory for %d transfers", n);
    }
    int left = n, stale = 0;
    for (int i = 0; i < n; i++) {
        x[i].g = &g[i];
        g[i].out = NULL;
        g[i].n = 0;
        g[i].missing = 0;
        g[i].cancelled = 0;
        stale |= g[i].stale != NULL;
        g[i].size = UINT64_MAX;
        char ek[4400];
        if (g[i].key[0] == '/' || strstr(g[i].key, "..") || !escape_key(g[i].key, ek, sizeof ek) ||
            snprintf(x[i].url, sizeof x[i].url, "%s/%s", s->t.base, ek) >= (int)sizeof x[i].url) {
            fail(s, &x[i], VV_ERR_FORMAT, "a key that is no relative path");
            left--;
        } else if (g[i].len != BS_ALL && g[i].len > g[i].max) {
            char what[200];
            snprintf(what, sizeof what, "%llu bytes to read (limit %llu)",
                     (unsigned long long)g[i].len, (unsigned long long)g[i].max);
            fail(s, &x[i], VV_ERR_LIMIT, what);
            left--;
        } else {
            cache_lookup(&x[i]);
            bs_count_open(&x[i].cnt, g[i].len == BS_ALL ? 0 : g[i].len);
        }
    }
    int active = 0;
    double checked = now_s();
    while (left > 0) {
        const double t = now_s();
        double next_retry = 0;
        if (stale && t - checked >= 0.05) { /* reads nobody wants any more: dropped */
            checked = t;
            for (int i = 0; i < n; i++)
                if (!x[i].done && g[i].stale && g[i].stale(g[i].stale_u)) {
                    active -= drop(m, &x[i]);
                    left--;
                }
        }
        for (int i = 0; i < n && active < cfg.in_flight; i++) {
            if (x[i].done || x[i].started)
                continue;
            if (g[i].stale && g[i].stale(g[i].stale_u)) {
                drop(m, &x[i]);
                left--;
                continue;
            }
            if (x[i].retry_at > t) {
                if (next_retry == 0 || x[i].retry_at < next_retry)
                    next_retry = x[i].retry_at;
                continue;
            }
            if (start(s, m, &x[i])) {
                active++;
            } else {
                left--;
                bs_count_close(&x[i].cnt, 1);
            }
        }
        int running = 0;
        curl_multi_perform(m, &running);
        CURLMsg *msg;
        int q;
        while ((msg = curl_multi_info_read(m, &q))) {
            if (msg->msg != CURLMSG_DONE)
                continue;
            xfer *xx = NULL;
            curl_easy_getinfo(msg->easy_handle, CURLINFO_PRIVATE, (char **)&xx);
            const CURLcode rc = msg->data.result;
            active--;
            bs_count_landed();
            finish(s, m, xx, rc);
            if (xx->done) {
                left--;
                bs_count_close(&xx->cnt, xx->status != VV_OK);
            } else if (xx->started) /* redirected: running again */
                active++;
        }
        if (left <= 0)
            break;
        if (active > 0) {
            curl_multi_poll(m, NULL, 0, 100, NULL);
        } else if (next_retry > 0) {
            double d = next_retry - now_s();
            if (stale && d > 0.05)
                d = 0.05; /* a retry's wait is no reason to miss a read going stale */
            if (d > 0) {
                struct timespec ts = {(time_t)d, (long)((d - (double)(time_t)d) * 1e9)};
                nanosleep(&ts, NULL);
            }
        }
    }
    vv_status first = VV_OK;
    for (int i = 0; i < n; i++) {
        if (x[i].e) {
            curl_multi_remove_handle(m, x[i].e);
            curl_easy_cleanup(x[i].e);
        }
        curl_slist_free_all(x[i].hdrs);
        http_resp_free(&x[i].r);
        bs_count_close(&x[i].cnt, x[i].status != VV_OK);
        if (first == VV_OK && x[i].status != VV_OK) {
            first = x[i].status;
            vv_error_set(first, "%s", x[i].msg);
        }
    }
    if (first != VV_OK)
        for (int i = 0; i < n; i++) {
            free(g[i].out);
            g[i].out = NULL;
        }
    pool_give(s, m);
    free(x);
    return first;
}

static void
http_close(vv_bytesrc *src) {
    bs_http *s = (bs_http *)src;
    for (int i = 0; i < s->npool; i++)
        curl_multi_cleanup(s->pool[i]);
    curl_share_cleanup(s->share);
    for (int i = 0; i < CURL_LOCK_DATA_LAST; i++)
        pthread_mutex_destroy(&s->share_lock[i]);
    pthread_mutex_destroy(&s->pool_lock);
    free(s);
}

static const vv_bytesrc_ops http_ops = {"http", http_get_many, http_close};

vv_bytesrc *
bs_remote(const char *root) {
    pthread_once(&cfg_once, cfg_init);
    pthread_mutex_lock(&registry_lock);
    bs_http *s = registry;
    while (s && strcmp(s->root, root))
        s = s->next;
    if (s) {
        pthread_mutex_unlock(&registry_lock);
        return &s->base;
    }
    s = calloc(1, sizeof *s);
    if (!s) {
        pthread_mutex_unlock(&registry_lock);
        vv_error_set(VV_ERR_NOMEM, "out of memory");
        return NULL;
    }
    const char *ep = getenv("AWS_ENDPOINT_URL_S3");
    if (!ep || !*ep)
        ep = getenv("AWS_ENDPOINT_URL");
    if (bs_target_parse(&s->t, root, ep, NULL) != VV_OK) {
        pthread_mutex_unlock(&registry_lock);
        free(s);
        return NULL;
    }
    if (s->t.s3)
        bs_target_credentials(&s->t);
    snprintf(s->root, sizeof s->root, "%s", root);
    s->base.ops = &http_ops;
    for (int i = 0; i < CURL_LOCK_DATA_LAST; i++)
        pthread_mutex_init(&s->share_lock[i], NULL);
    pthread_mutex_init(&s->pool_lock, NULL);
    s->share = curl_share_init();
    if (!s->share) {
        pthread_mutex_unlock(&registry_lock);
        http_close(&s->base);
        vv_error_set(VV_ERR_NOMEM, "out of memory");
        return NULL;
    }
    curl_share_setopt(s->share, CURLSHOPT_LOCKFUNC, share_lock);
    curl_share_setopt(s->share, CURLSHOPT_UNLOCKFUNC, share_unlock);
    curl_share_setopt(s->share, CURLSHOPT_USERDATA, s);
    curl_share_setopt(s->share, CURLSHOPT_SHARE, CURL_LOCK_DATA_DNS);
    curl_share_setopt(s->share, CURLSHOPT_SHARE, CURL_LOCK_DATA_SSL_SESSION);
    s->next = registry;
    registry = s;
    pthread_mutex_unlock(&registry_lock);
    return &s->base;
}

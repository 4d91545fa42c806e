/*
 * volvis serve: the browser view. One libwebsockets context serves the
 * page (the files of web/, installed as share/volvis/web) over HTTP and
 * talks to each page over one WebSocket (docs/serve-protocol.md). Every
 * request needs the access token printed at the start (compared in
 * constant time, then kept in an HttpOnly SameSite=Strict cookie); the
 * WebSocket upgrade also needs the page's own Origin. Paths a client names
 * are opened beneath --root; URLs only as given on the command line or under
 * --allow-url. A malformed message closes that client only.
 */
#define _GNU_SOURCE
#include <errno.h>
#include <libwebsockets.h>
#include <limits.h>
#include <pthread.h>
#include <signal.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/random.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "serve.h"

_Static_assert(SRV_PRE >= LWS_PRE, "SRV_PRE must hold LWS_PRE");

#ifndef VOLVIS_WEB_SOURCE_DIR
#define VOLVIS_WEB_SOURCE_DIR ""
#endif
#ifndef VOLVIS_WEB_INSTALL_DIR
#define VOLVIS_WEB_INSTALL_DIR ""
#endif

/* 24 random bytes: 192 bits, as 48 hex digits. */
#define TOKEN_BYTES 24
static char token[2 * TOKEN_BYTES + 1];

static srv_server server;
static volatile sig_atomic_t interrupted;

static const cli_opt_spec serve_opts[] = {
    {"port", 'p', "N"},        {"bind", 0, "ADDR"},
    {"root", 0, "DIR"},        {"memory-limit", 0, "BYTES[K|M|G]"},
    {"allow-remote", 0, NULL}, {"cert", 0, "FILE"},
    {"key", 0, "FILE"},        {"shared", 0, NULL},
    {"threads", 0, "N"},       {"web", 0, "DIR"},
    {"verbose", 'v', NULL},    {"allow-url", 0, "PREFIX"},
};
#define N_SERVE_OPTS ((int)(sizeof serve_opts / sizeof serve_opts[0]))

void
cli_serve_usage(FILE *out) {
    fprintf(out,
            "usage: volvis serve [OPTIONS] [FILE|SCENE|FOLDER] [URL...]\n"
            "\n"
            "Serves the browser view: prints one URL with a fresh access token (open it in\n"
            "Chromium or Firefox). The page shows a 3-D view (drag to rotate, right-drag or\n"
            "shift-drag to pan, wheel to zoom), axial, coronal and sagittal slices with the\n"
            "value under the pointer, transfer-function presets, the mode, channels, time\n"
            "steps, a file browser limited to the root folder, Save session and PNG. Frames\n"
            "are rendered here and sent as JPEG: reduced ray casts while the view moves, the\n"
            "full frame when it stops (what `volvis render` of the saved session draws).\n"
            "Each browser tab has its own session unless --shared. FILE or SCENE opens in\n"
            "every new session; a FOLDER is the root with nothing open. Runs until Ctrl-C.\n"
            "\n"
            "URLs (http://, https://, s3://bucket/key) given here are the remote data the\n"
            "page may open, listed atop its Files; the first opens in every new session when\n"
            "no FILE or SCENE is given. The page can open no other URL but those under an\n"
            "--allow-url PREFIX: the server fetches nothing a browser names otherwise.\n"
            "Files, a scene's files too, are opened beneath the root only (docs/security.md).\n"
            "\n"
            "Options:\n"
            "  -p, --port N       TCP port (default 8765; 0: any free port)\n"
            "  --bind ADDR        address to listen on (default 127.0.0.1); any other than\n"
            "                     127.0.0.1, ::1 or localhost needs --allow-remote\n"
            "  --allow-remote     allow --bind to a non-loopback address (put TLS in front:\n"
            "                     --cert/--key, or an SSH tunnel; see docs/serve.md)\n"
            "  --cert FILE, --key FILE  serve HTTPS and WSS with this certificate and key\n"
            "  --root DIR         the folder the file browser, open and save may reach\n"
            "                     (default: FOLDER, else FILE's folder, else the current one)\n"
            "  --allow-url PREFIX a URL prefix (repeatable) the page may open URLs under, on a\n"
            "                     path-segment boundary: https://host/data/ takes\n"
            "                     https://host/data/a.zarr, never https://host/database\n"
            "  --memory-limit BYTES  one budget for the voxels of every session (K, M, G\n"
            "                     suffixes); files open out of core under it\n"
            "  --shared           one session for every tab: people see and steer one view\n"
            "  --threads N        render threads (default: all cores)\n"
            "  --web DIR          serve the client from DIR (default: the installed one)\n"
            "  -v, --verbose      log every connection and closed client\n"
            "  -h, --help         show this help\n"
            "\n"
            "Examples:\n"
            "  volvis serve ../shared/data/volumes/ct_head.nrrd\n"
            "  volvis serve --root /data/scans --memory-limit 4G /data/scans\n"
            "  volvis serve --memory-limit 4G https://example.org/data/img.ome.zarr\n"
            "  volvis serve --allow-url s3://bucket/images/ /data/scans\n"
            "  ssh -L 8765:127.0.0.1:8765 server volvis serve big.zarr   # from a laptop\n");
}

void
srv_wake(srv_server *srv) {
    if (srv->context)
        lws_cancel_service((struct lws_context *)srv->context);
}

/* Constant-time comparison of @p got (length @p n) with the token. */
static int
token_ok(const char *got, size_t n) {
    const size_t want = sizeof token - 1;
    unsigned diff = n != want;
    for (size_t i = 0; i < want; i++)
        diff |= (unsigned)(unsigned char)token[i] ^ (unsigned)(unsigned char)(i < n ? got[i] : 0);
    return diff == 0;
}

/* The token of the request's cookie "volvis_token=..." (1 when it matches). */
static int
cookie_ok(struct lws *wsi) {
    char buf[2048];
    int n = lws_hdr_total_length(wsi, WSI_TOKEN_HTTP_COOKIE);
    if (n <= 0 || n >= (int)sizeof buf ||
        lws_hdr_copy(wsi, buf, sizeof buf, WSI_TOKEN_HTTP_COOKIE) < 0)
        return 0;
    int ok = 0;
    for (char *save = NULL, *p = strtok_r(buf, ";", &save); p; p = strtok_r(NULL, ";", &save)) {
        while (*p == ' ')
            p++;
        if (strncmp(p, "volvis_token=", 13) == 0)
            ok |= token_ok(p + 13, strlen(p + 13));
    }
    return ok;
}

/* 1 when the URL's query holds token=T; 0 when it holds none; -1 a wrong one. */
static int
urlarg_token(struct lws *wsi) {
    char buf[256];
    const char *v = lws_get_urlarg_by_name(wsi, "token=", buf, sizeof buf);
    if (!v)
        return 0;
    return token_ok(v, strlen(v)) ? 1 : -1;
}

static const char *
mime_of(const char *path) {
    const char *dot = strrchr(path, '.');
    static const struct {
        const char *ext, *mime;
    } types[] = {{".html", "text/html; charset=utf-8"},
                 {".js", "text/javascript; charset=utf-8"},
                 {".css", "text/css; charset=utf-8"},
                 {".png", "image/png"},
                 {".svg", "image/svg+xml"},
                 {".json", "application/json"},
                 {".ico", "image/x-icon"}};
    for (size_t i = 0; dot && i < sizeof types / sizeof types[0]; i++)
        if (strcmp(dot, types[i].ext) == 0)
            return types[i].mime;
    return NULL;
}

/* The security headers every answer carries, and the cookie when @p set_cookie. */
static int
add_headers(struct lws *wsi, unsigned char **p, unsigned char *end, int set_cookie) {
    static const char *const hdr[][2] = {
        {"cache-control:", "no-store"},
        {"referrer-policy:", "no-referrer"},
        {"x-content-type-options:", "nosniff"},
        {"x-frame-options:", "DENY"},
        {"content-security-policy:",
         "default-src 'self'; img-src 'self' blob: data:; connect-src 'self'; style-src 'self'; "
         "frame-ancestors 'none'"}};
    for (size_t i = 0; i < sizeof hdr / sizeof hdr[0]; i++)
        if (lws_add_http_header_by_name(wsi, (const unsigned char *)hdr[i][0],
                                        (const unsigned char *)hdr[i][1], (int)strlen(hdr[i][1]), p,
                                        end))
            return -1;
    if (set_cookie) {
        char cookie[256];
        int n = snprintf(cookie, sizeof cookie,
                         "volvis_token=%s; HttpOnly; SameSite=Strict; Path=/", token);
        if (lws_add_http_header_by_name(wsi, (const unsigned char *)"set-cookie:",
                                        (const unsigned char *)cookie, n, p, end))
            return -1;
    }
    return 0;
}

/* Writes a bare status (403, 404, 405) with the security headers and a one-line text. */
static int
write_status(struct lws *wsi, unsigned status, const char *text) {
    unsigned char buf[LWS_PRE + 2048], *start = buf + LWS_PRE, *p = start,
                                       *end = buf + sizeof buf - 1;
    size_t n = strlen(text);
    if (lws_add_http_common_headers(wsi, status, "text/plain; charset=utf-8", (lws_filepos_t)n, &p,
                                    end) ||
        add_headers(wsi, &p, end, 0) || lws_finalize_write_http_header(wsi, start, &p, end))
        return -1;
    unsigned char body[LWS_PRE + 256];
    if (n > sizeof body - LWS_PRE)
        n = sizeof body - LWS_PRE;
    memcpy(body + LWS_PRE, text, n);
    return lws_write(wsi, body + LWS_PRE, n, LWS_WRITE_HTTP_FINAL) == (int)n ? 0 : -1;
}

/* Answers a request with a bare status and ends the transaction. */
static int
answer_status(struct lws *wsi, unsigned status, const char *text) {
    if (write_status(wsi, status, text))
        return -1;
    return lws_http_transaction_completed(wsi) ? -1 : 0;
}

/* A page file for URI @p uri: names of [A-Za-z0-9._-] in at most two parts, no "..". */
static int
web_path(const char *uri, char *out, size_t cap) {
    if (strcmp(uri, "/") == 0 || uri[0] == '\0')
        uri = "/index.html";
    if (uri[0] != '/' || strlen(uri) > 200 || strstr(uri, ".."))
        return -1;
    int slashes = 0;
    for (const char *c = uri + 1; *c; c++) {
        if (*c == '/') {
            if (++slashes > 1 || c[-1] == '/')
                return -1;
        } else if (!(*c >= 'a' && *c <= 'z') && !(*c >= 'A' && *c <= 'Z') &&
                   !(*c >= '0' && *c <= '9') && *c != '.' && *c != '_' && *c != '-') {
            return -1;
        }
    }
    if (uri[1] == '.' || !mime_of(uri))
        return -1;
    if ((size_t)snprintf(out, cap, "%s%s", server.web_dir, uri) >= cap)
        return -1;
    struct stat st;
    return stat(out, &st) == 0 && S_ISREG(st.st_mode) ? 0 : -1;
}

static int
serve_http(struct lws *wsi, const char *uri) {
    if (lws_hdr_total_length(wsi, WSI_TOKEN_GET_URI) <= 0)
        return answer_status(wsi, HTTP_STATUS_METHOD_NOT_ALLOWED, "only GET\n");
    int arg = urlarg_token(wsi);
    int cookie = cookie_ok(wsi);
    if (arg < 0 || (arg == 0 && !cookie)) {
        if (server.verbose)
            fprintf(stderr, "volvis: serve: 403 for %s (no valid token)\n", uri);
        return answer_status(wsi, HTTP_STATUS_FORBIDDEN,
                             "403: open the URL volvis serve printed (it holds the token)\n");
    }
    char path[PATH_MAX];
    if (web_path(uri, path, sizeof path))
        return answer_status(wsi, HTTP_STATUS_NOT_FOUND, "404: not found\n");
    unsigned char hdr[1024], *p = hdr, *end = hdr + sizeof hdr;
    if (add_headers(wsi, &p, end, arg > 0))
        return -1;
    int n = lws_serve_http_file(wsi, path, mime_of(path), (const char *)hdr, (int)(p - hdr));
    if (n < 0 || (n > 0 && lws_http_transaction_completed(wsi)))
        return -1;
    return 0;
}

/* The WebSocket upgrade: the token's cookie, path /ws and the page's own Origin. */
static int
upgrade_allowed(struct lws *wsi, char *why, size_t cap) {
    char uri[256], origin[512], host[512];
    if (lws_hdr_copy(wsi, uri, sizeof uri, WSI_TOKEN_GET_URI) < 0 || strcmp(uri, "/ws") != 0) {
        snprintf(why, cap, "upgrade of a path other than /ws");
        return 0;
    }
    if (!cookie_ok(wsi)) {
        snprintf(why, cap, "upgrade without the token's cookie");
        return 0;
    }
    if (lws_hdr_copy(wsi, origin, sizeof origin, WSI_TOKEN_ORIGIN) <= 0 ||
        lws_hdr_copy(wsi, host, sizeof host, WSI_TOKEN_HOST) <= 0) {
        snprintf(why, cap, "upgrade without Origin or Host");
        return 0;
    }
    char want[600];
    snprintf(want, sizeof want, "%s://%s", lws_is_ssl(wsi) ? "https" : "http", host);
    if (strcmp(origin, want) != 0) {
        snprintf(why, cap, "upgrade from Origin '%.100s' (not %.100s)", origin, want);
        return 0;
    }
    return 1;
}

static void
close_with(struct lws *wsi, srv_client *c, int code, const char *reason) {
    if (server.verbose || code != LWS_CLOSE_STATUS_NORMAL)
        fprintf(stderr, "volvis: serve: client %llu closed: %s\n", (unsigned long long)c->id,
                reason);
    lws_close_reason(wsi, (enum lws_close_status)code, (unsigned char *)reason, strlen(reason));
}

static void
client_gone(srv_client *c) {
    if (!c->session)
        return;
    pthread_mutex_lock(&server.lock);
    for (srv_client **p = &server.clients; *p; p = &(*p)->next)
        if (*p == c) {
            *p = c->next;
            break;
        }
    pthread_mutex_unlock(&server.lock);
    srv_session *s = c->session;
    int left = srv_session_detach(s, c);
    if (left == 0 && s != server.shared_session)
        srv_session_free(s);
    c->session = NULL;
    free(c->rx);
    c->rx = NULL;
}

/* The per-connection data of libwebsockets: a pointer to the client. */
typedef struct conn {
    srv_client *client;
} conn;

/* Clients are kept in a list for EVENT_WAIT_CANCELLED; a client's list link
 * is its `next` within the session, so the server keeps its own. */
typedef struct client_link {
    srv_client *c;
    struct client_link *next;
} client_link;
static client_link *links;

static void
link_add(srv_client *c) {
    client_link *l = malloc(sizeof *l);
    if (!l)
        return;
    l->c = c;
    l->next = links;
    links = l;
}

static void
link_remove(srv_client *c) {
    for (client_link **p = &links; *p; p = &(*p)->next)
        if ((*p)->c == c) {
            client_link *l = *p;
            *p = l->next;
            free(l);
            return;
        }
}

/* ---- remote data pending (docs/serve-protocol.md, `remote`) ---------------------------------- */

/* The reads of remote stores not yet answered, as every client last heard
 * them (service thread); a watcher thread wakes the service four times a
 * second while they change, and the service gives each client a `remote`
 * message when they did: into its latest-state slot (srv_session_send_latest),
 * which a newer one replaces and nothing drops, so the last counts (pending
 * 0 once every read is answered) reach every client, however slowly it
 * reads. */
static vv_remote_stats remote_sent;
static atomic_int remote_stop;
static pthread_t remote_thread;
static int remote_started;

static void *
remote_watch(void *arg) {
    (void)arg;
    vv_remote_stats last = {0};
    while (!atomic_load(&remote_stop)) {
        struct timespec ts = {0, 250 * 1000 * 1000};
        nanosleep(&ts, NULL);
        vv_remote_stats st;
        vv_remote_stats_get(&st);
        if (st.pending != last.pending || st.pending_bytes != last.pending_bytes) {
            last = st;
            srv_wake(&server);
        }
    }
    return NULL;
}

/* A `remote` message to every client when the counts changed since the last (service thread). */
static void
remote_send(void) {
    vv_remote_stats st;
    vv_remote_stats_get(&st);
    if (st.pending == remote_sent.pending && st.pending_bytes == remote_sent.pending_bytes)
        return;
    remote_sent = st;
    char text[200];
    snprintf(text, sizeof text,
             "{\"type\":\"remote\",\"pending\":%llu,\"pending_bytes\":%llu,\"in_flight\":%llu,"
             "\"completed\":%llu,\"bytes_received\":%llu}",
             (unsigned long long)st.pending, (unsigned long long)st.pending_bytes,
             (unsigned long long)st.in_flight, (unsigned long long)st.completed,
             (unsigned long long)st.bytes_received);
    for (client_link *l = links; l; l = l->next)
        if (l->c->session)
            srv_session_send_latest(l->c->session, l->c, text);
}

static int
callback(struct lws *wsi, enum lws_callback_reasons reason, void *user, void *in, size_t len) {
    conn *pc = user;
    srv_client *c = pc ? pc->client : NULL;
    char why[300];
    switch (reason) {
    case LWS_CALLBACK_HTTP:
        return serve_http(wsi, (const char *)in);
    case LWS_CALLBACK_HTTP_CONFIRM_UPGRADE:
        if (!upgrade_allowed(wsi, why, sizeof why)) {
            fprintf(stderr, "volvis: serve: refused: %s\n", why);
            /* >0: answered here (libwebsockets ends the transaction) */
            return write_status(wsi, HTTP_STATUS_FORBIDDEN, "403: refused\n") ? -1 : 1;
        }
        return 0;
    case LWS_CALLBACK_FILTER_PROTOCOL_CONNECTION:
        /* the second line: HTTP_CONFIRM_UPGRADE saw the same headers */
        return upgrade_allowed(wsi, why, sizeof why) ? 0 : -1;
    case LWS_CALLBACK_ESTABLISHED: {
        c = calloc(1, sizeof *c);
        if (!c)
            return -1;
        c->wsi = wsi;
        pthread_mutex_lock(&server.lock);
        c->id = ++server.next_client_id;
        srv_session *s = server.shared ? server.shared_session : NULL;
        pthread_mutex_unlock(&server.lock);
        if (!s && !(s = srv_session_new(&server))) {
            free(c);
            return -1;
        }
        srv_session_attach(s, c);
        link_add(c);
        pc->client = c;
        if (server.verbose)
            fprintf(stderr, "volvis: serve: client %llu connected\n", (unsigned long long)c->id);
        return 0;
    }
    case LWS_CALLBACK_RECEIVE: {
        if (!c || !c->session)
            return -1;
        if (lws_frame_is_binary(wsi)) {
            close_with(wsi, c, LWS_CLOSE_STATUS_UNACCEPTABLE_OPCODE,
                       "binary messages are not "
                       "accepted");
            return -1;
        }
        if (c->rx_len + len > SRV_MSG_MAX) {
            snprintf(why, sizeof why, "message over %d bytes", SRV_MSG_MAX);
            close_with(wsi, c, LWS_CLOSE_STATUS_MESSAGE_TOO_LARGE, why);
            return -1;
        }
        char *rx = realloc(c->rx, c->rx_len + len + 1);
        if (!rx)
            return -1;
        c->rx = rx;
        memcpy(c->rx + c->rx_len, in, len);
        c->rx_len += len;
        if (!lws_is_final_fragment(wsi))
            return 0;
        srv_msg m;
        int rc = srv_msg_parse(c->rx, c->rx_len, &m, why, sizeof why);
        c->rx_len = 0;
        if (rc) {
            close_with(wsi, c, LWS_CLOSE_STATUS_POLICY_VIOLATION, why);
            return -1;
        }
        srv_session_handle(c->session, c, &m);
        if (srv_session_has_out(c->session, c))
            lws_callback_on_writable(wsi);
        return 0;
    }
    case LWS_CALLBACK_SERVER_WRITEABLE: {
        if (!c || !c->session)
            return -1;
        int code = srv_session_close_code(c->session, c, why, sizeof why);
        if (code) {
            close_with(wsi, c, code, why);
            return -1;
        }
        srv_buf *b = srv_session_next_out(c->session, c);
        if (!b)
            return 0;
        int n = lws_write(wsi, b->data + SRV_PRE, b->len,
                          b->binary ? LWS_WRITE_BINARY : LWS_WRITE_TEXT);
        srv_buf_unref(b);
        if (n < 0)
            return -1;
        if (srv_session_has_out(c->session, c))
            lws_callback_on_writable(wsi);
        return 0;
    }
    case LWS_CALLBACK_CLOSED:
        if (c) {
            link_remove(c);
            client_gone(c);
            if (server.verbose)
                fprintf(stderr, "volvis: serve: client %llu left\n", (unsigned long long)c->id);
            free(c);
            pc->client = NULL;
        }
        return 0;
    case LWS_CALLBACK_EVENT_WAIT_CANCELLED:
        remote_send();
        for (client_link *l = links; l; l = l->next)
            if (l->c->session && srv_session_has_out(l->c->session, l->c))
                lws_callback_on_writable((struct lws *)l->c->wsi);
        return 0;
    default:
        break;
    }
    return lws_callback_http_dummy(wsi, reason, user, in, len);
}

static const struct lws_protocols protocols[] = {
    {"http", callback, sizeof(conn), 0, 0, NULL, 0},
    {"volvis", callback, sizeof(conn), 65536, 0, NULL, 0},
    {NULL, NULL, 0, 0, 0, NULL, 0}};

static void
on_signal(int sig) {
    (void)sig;
    interrupted = 1;
    if (server.context)
        lws_cancel_service((struct lws_context *)server.context);
}

static void
lws_log(int level, const char *line) {
    (void)level;
    fprintf(stderr, "volvis: serve: libwebsockets: %s", line);
}

/* The client's files: --web, $VOLVIS_WEB_DIR, the installed folder, the source tree's. */
static int
find_web_dir(const char *given) {
    const char *cands[4] = {given, getenv("VOLVIS_WEB_DIR"), NULL, VOLVIS_WEB_SOURCE_DIR};
    char installed[PATH_MAX + 32];
    char exe[PATH_MAX - 64];
    ssize_t n = readlink("/proc/self/exe", exe, sizeof exe - 1);
    if (n > 0) {
        exe[n] = '\0';
        char *slash = strrchr(exe, '/');
        if (slash) {
            *slash = '\0';
            snprintf(installed, sizeof installed, "%s/../share/volvis/web", exe);
            cands[2] = installed;
        }
    }
    for (int i = 0; i < 4; i++) {
        char index[PATH_MAX + 16];
        if (!cands[i] || !cands[i][0])
            continue;
        snprintf(index, sizeof index, "%s/index.html", cands[i]);
        if (access(index, R_OK) == 0 && realpath(cands[i], server.web_dir))
            return 0;
        if (i == 0) {
            cli_error("serve: --web %s: no index.html there", given);
            return -1;
        }
    }
    cli_error("serve: the browser client's files (share/volvis/web) are not installed; give "
              "--web DIR");
    return -1;
}

static int
is_loopback(const char *addr) {
    return strcmp(addr, "127.0.0.1") == 0 || strcmp(addr, "::1") == 0 ||
           strcmp(addr, "localhost") == 0;
}

int
cli_serve_main(int argc, char **argv) {
    cli_args a;
    int rc = cli_parse(&a, "serve", serve_opts, N_SERVE_OPTS, argc, argv);
    if (rc == CLI_HELP) {
        cli_serve_usage(stdout);
        return CLI_EXIT_OK;
    }
    if (rc)
        return rc;
    int n_files = 0;
    const char *input = NULL;
    for (int i = 0; i < a.n_pos; i++)
        if (!srv_is_url(a.pos[i])) {
            n_files++;
            input = a.pos[i];
        }
    if (n_files > 1)
        return cli_usage_error(&a, "expected at most one FILE, SCENE or FOLDER, got %d", n_files);
    memset(&server, 0, sizeof server);
    /* for tests and old kernels' behaviour: the walk that replaces openat2 */
    if (getenv("VOLVIS_SERVE_NO_OPENAT2") && strcmp(getenv("VOLVIS_SERVE_NO_OPENAT2"), "0"))
        srv_openat2_off = 1;
    /* the URLs and prefixes, in normal form (what a client's URL is compared with) */
    server.urls = calloc((size_t)a.n_pos + 1, sizeof *server.urls);
    server.prefixes = calloc((size_t)cli_count(&a, "allow-url") + 1, sizeof *server.prefixes);
    if (!server.urls || !server.prefixes) {
        cli_error("serve: out of memory");
        return CLI_EXIT_FAIL;
    }
    for (int i = 0; i < a.n_pos + a.n_seen; i++) {
        const char *u = i < a.n_pos ? a.pos[i] : a.seen[i - a.n_pos].value;
        if (i < a.n_pos ? !srv_is_url(u)
                        : strcmp(a.specs[a.seen[i - a.n_pos].opt].name, "allow-url") != 0)
            continue;
        char norm[SRV_URL_MAX], why[512];
        if (srv_url_normalize(u, norm, sizeof norm, why, sizeof why))
            return cli_usage_error(&a, "%s%s", i < a.n_pos ? "" : "--allow-url ", why);
        if (i >= a.n_pos && strchr(norm, '?'))
            return cli_usage_error(&a, "--allow-url %s: a prefix has no query", u);
        char *copy = strdup(norm);
        if (!copy) {
            cli_error("serve: out of memory");
            return CLI_EXIT_FAIL;
        }
        if (i < a.n_pos)
            server.urls[server.n_urls++] = copy;
        else
            server.prefixes[server.n_prefixes++] = copy;
    }
    pthread_mutex_init(&server.lock, NULL);
    /* a remote user chooses the files: every parser, our own too, reads them in the
     * reader sandbox (docs/security.md), unless the environment says otherwise */
    setenv("VOLVIS_SANDBOX", "all", 0);
    int port = 8765;
    const char *s;
    if ((s = cli_get(&a, "port")) && (rc = cli_parse_int(&a, "port", s, 0, 65535, &port)))
        return rc;
    if ((s = cli_get(&a, "threads")) &&
        (rc = cli_parse_int(&a, "threads", s, 1, 1024, &server.threads)))
        return rc;
    if ((s = cli_get(&a, "memory-limit")) &&
        (rc = cli_parse_bytes(&a, "memory-limit", s, &server.memory_limit)))
        return rc;
    const char *bind = cli_get(&a, "bind") ? cli_get(&a, "bind") : "127.0.0.1";
    if (!is_loopback(bind) && !cli_count(&a, "allow-remote"))
        return cli_usage_error(&a,
                               "--bind %s: not a loopback address; add --allow-remote (and "
                               "--cert/--key, or an SSH tunnel: see docs/serve.md)",
                               bind);
    const char *cert = cli_get(&a, "cert"), *key = cli_get(&a, "key");
    if (!cert != !key)
        return cli_usage_error(&a, "--cert and --key go together");
    if (cert && ((rc = cli_check_readable(cert)) || (rc = cli_check_readable(key))))
        return rc;
    server.shared = cli_count(&a, "shared") > 0;
    server.verbose = cli_count(&a, "verbose") > 0;

    /* the data and the root */
    char real[PATH_MAX];
    struct stat st;
    int folder = 0;
    if (input) {
        if (!realpath(input, real) || stat(real, &st) != 0) {
            cli_error("%s: %s", input, strerror(errno));
            return CLI_EXIT_FAIL;
        }
        /* a folder that holds one dataset (an OME-Zarr store) opens; any other is the root */
        folder = S_ISDIR(st.st_mode) && !srv_folder_is_store(real) && !cli_get(&a, "root");
    }
    const char *root = cli_get(&a, "root");
    char root_real[PATH_MAX];
    if (root) {
        if (!realpath(root, root_real) || stat(root_real, &st) != 0 || !S_ISDIR(st.st_mode)) {
            cli_error("serve: --root %s: not a folder", root);
            return CLI_EXIT_USAGE;
        }
    } else if (input && folder) {
        snprintf(root_real, sizeof root_real, "%s", real);
    } else if (input) {
        snprintf(root_real, sizeof root_real, "%s", real);
        char *slash = strrchr(root_real, '/');
        if (slash == root_real)
            slash[1] = '\0';
        else if (slash)
            *slash = '\0';
    } else if (!getcwd(root_real, sizeof root_real)) {
        cli_error("serve: the current folder: %s", strerror(errno));
        return CLI_EXIT_FAIL;
    }
    snprintf(server.root, sizeof server.root, "%s", root_real);
    if (input && !folder) {
        size_t rl = strlen(server.root);
        if (strncmp(real, server.root, rl) != 0 || (real[rl] != '/' && rl > 1)) {
            cli_error("serve: %s lies outside --root %s", input, server.root);
            return CLI_EXIT_USAGE;
        }
        snprintf(server.initial, sizeof server.initial, "%s", real);
        /* a file that does not open is reported now, not in every tab */
        if ((rc = cli_check_readable_input(real)))
            return rc;
        /* a scene's files are read beneath the root only, as the page's are */
        char why[1024];
        if (srv_scene_confined(server.root, real, server.urls, server.n_urls, server.prefixes,
                               server.n_prefixes, why, sizeof why)) {
            cli_error("serve: %s (give a --root that holds the scene's files)", why);
            return CLI_EXIT_USAGE;
        }
    } else if (!input && server.n_urls > 0) {
        /* no file: the first URL opens in every new session (the door's error, if it
         * cannot, reaches each page as one line) */
        snprintf(server.initial, sizeof server.initial, "%s", server.urls[0]);
    }
    /* every reader the door starts reads beneath the root only (its Landlock layer,
     * src/sandbox/policy.c): a link swapped into the root after the server's check
     * leads no reader out of it */
    setenv("VOLVIS_SANDBOX_BENEATH", server.root, 1);
    /* under mpirun: rank 0 serves, the others render with it */
    server.ranks = 1;
    int rank = 0;
    if (vv_parallel_launched()) {
        vv_error_clear();
        vv_status ps = vv_parallel_init(NULL, NULL, &rank, &server.ranks);
        if (ps == VV_OK && server.ranks > 1)
            ps = srv_mpi_start();
        if (ps != VV_OK)
            return cli_fail(ps, NULL);
        if (rank > 0) {
            cli_errors_quiet(1);
            return srv_mpi_worker(&server);
        }
    }
    if (find_web_dir(cli_get(&a, "web"))) {
        if (server.ranks > 1)
            srv_mpi_stop();
        return CLI_EXIT_FAIL;
    }
    if (getrandom(token, TOKEN_BYTES, 0) != TOKEN_BYTES) {
        cli_error("serve: no random bytes for the token: %s", strerror(errno));
        if (server.ranks > 1)
            srv_mpi_stop();
        return CLI_EXIT_FAIL;
    }
    {
        unsigned char raw[TOKEN_BYTES];
        memcpy(raw, token, TOKEN_BYTES);
        for (int i = 0; i < TOKEN_BYTES; i++)
            snprintf(token + 2 * i, 3, "%02x", raw[i]);
    }
    if (server.threads > 0)
        vv_threads_set(server.threads);

    lws_set_log_level(LLL_ERR | (server.verbose ? LLL_WARN : 0), lws_log);
    struct lws_context_creation_info info;
    memset(&info, 0, sizeof info);
    info.port = port;
    info.iface = bind;
    info.protocols = protocols;
    info.gid = (gid_t)-1;
    info.uid = (uid_t)-1;
    info.options = LWS_SERVER_OPTION_VALIDATE_UTF8;
    if (strchr(bind, ':') == NULL)
        info.options |= LWS_SERVER_OPTION_DISABLE_IPV6;
    if (cert) {
        info.options |= LWS_SERVER_OPTION_DO_SSL_GLOBAL_INIT;
        info.ssl_cert_filepath = cert;
        info.ssl_private_key_filepath = key;
    }
    info.timeout_secs = 30;
    struct lws_context *ctx = lws_create_context(&info);
    if (!ctx) {
        cli_error("serve: cannot listen on %s port %d (in use, or no such address)", bind, port);
        if (server.ranks > 1)
            srv_mpi_stop();
        return CLI_EXIT_FAIL;
    }
    server.context = ctx;
    if (server.shared && !(server.shared_session = srv_session_new(&server))) {
        cli_error("serve: cannot start the shared session");
        lws_context_destroy(ctx);
        if (server.ranks > 1)
            srv_mpi_stop();
        return CLI_EXIT_FAIL;
    }
    struct lws_vhost *vh = lws_get_vhost_by_name(ctx, "default");
    int real_port = vh ? lws_get_vhost_listen_port(vh) : port;
    signal(SIGINT, on_signal);
    signal(SIGTERM, on_signal);
    signal(SIGPIPE, SIG_IGN);
    if (!is_loopback(bind))
        fprintf(stderr,
                "volvis: serve: warning: listening on %s: anyone who can reach it and has the "
                "token sees the data%s\n",
                bind, cert ? "" : "; without --cert/--key the token travels in clear text");
    const char *host = strchr(bind, ':')              ? "[::1]"
                       : strcmp(bind, "0.0.0.0") == 0 ? "127.0.0.1"
                                                      : bind;
    printf("%s://%s:%d/?token=%s\n", cert ? "https" : "http", host, real_port, token);
    fflush(stdout);
    fprintf(stderr, "volvis: serve: root %s%s%s%s; Ctrl-C stops\n", server.root,
            server.initial[0] ? ", showing " : "", server.initial,
            server.ranks > 1 ? ", every frame rendered by all MPI ranks" : "");
    if (server.verbose)
        fprintf(stderr, "volvis: serve: the page's files from %s\n", server.web_dir);
    remote_started = pthread_create(&remote_thread, NULL, remote_watch, NULL) == 0;
    while (!interrupted) {
        if (lws_service(ctx, 0) < 0)
            break;
        /* frames the render threads posted for all ranks (MPI calls stay on this thread) */
        if (server.ranks > 1)
            srv_mpi_service(&server);
    }
    pthread_mutex_lock(&server.lock);
    server.stopping = 1; /* a render thread waiting on a frame of all ranks is released */
    pthread_mutex_unlock(&server.lock);
    if (server.ranks > 1)
        srv_mpi_service(&server);
    atomic_store(&remote_stop, 1);
    if (remote_started)
        pthread_join(remote_thread, NULL);
    lws_context_destroy(ctx);
    server.context = NULL;
    srv_session_free(server.shared_session);
    if (server.ranks > 1)
        srv_mpi_stop();
    while (links)
        link_remove(links->c);
    fprintf(stderr, "volvis: serve: stopped\n");
    return CLI_EXIT_OK;
}

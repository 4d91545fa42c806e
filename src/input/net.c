/*
 * The network driver: raw events from other processes over a Unix-domain
 * stream socket, one text line each (docs/input.md, "Network protocol").
 */
#include <errno.h>
#include <fcntl.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include "input_internal.h"

#define NET_MAX_CLIENTS 16
#define NET_MAX_CLIENT_DEVICES 8

typedef struct net_client {
    int fd; /* -1: free */
    char buf[VV_INPUT_LINE_MAX + 2];
    size_t len;
    int overflow; /* discarding the rest of an over-long line */
    int line;
    int local[NET_MAX_CLIENT_DEVICES];
    int id[NET_MAX_CLIENT_DEVICES];
    int n_dev;
} net_client;

typedef struct net_server {
    int index; /* driver index */
    int lfd;
    char path[sizeof(((struct sockaddr_un *)0)->sun_path)];
    net_client c[NET_MAX_CLIENTS];
} net_server;

static void
reply(int fd, const char *fmt, const char *a, int line) {
    char out[256];
    int n = snprintf(out, sizeof out, fmt, line, a);
    if (n > 0)
        (void)!send(fd, out, (size_t)n < sizeof out ? (size_t)n : sizeof out - 1,
                    MSG_NOSIGNAL | MSG_DONTWAIT);
}

static void
client_drop(vv_input_manager *m, net_client *c, double now) {
    for (int i = 0; i < c->n_dev; i++) {
        vv_input_raw_event ev;
        memset(&ev, 0, sizeof ev);
        ev.device = c->id[i];
        ev.time = now;
        ev.kind = VV_RAW_REMOVED;
        vv_input_manager_feed(m, &ev);
    }
    vv_input_unwatch(m, c->fd);
    close(c->fd);
    c->fd = -1;
    c->n_dev = 0;
}

static void
client_line(vv_input_manager *m, net_client *c, char *line, double now) {
    char err[160];
    c->line++;
    char *hash = strchr(line, '#');
    if (hash)
        *hash = '\0';
    char *tok[16];
    int nt = vv_input_tokenize(line, tok, 15);
    if (nt == 0)
        return;
    if (nt > 15) {
        snprintf(err, sizeof err, "too many fields");
        goto bad;
    }
    if (strcmp(tok[0], "device") == 0) {
        int local;
        vv_input_kind kind;
        char *end;
        long v = nt >= 3 ? strtol(tok[1], &end, 10) : 0;
        if (nt < 3 || *end || v < 1 || v > 1000000) {
            snprintf(err, sizeof err, "'device' takes an id (1..1000000), a kind and a name");
            goto bad;
        }
        local = (int)v;
        if (vv_input_kind_parse(tok[2], &kind) != VV_OK) {
            vv_error_clear();
            snprintf(err, sizeof err, "unknown device kind '%.32s'", tok[2]);
            goto bad;
        }
        for (int i = 0; i < c->n_dev; i++)
            if (c->local[i] == local) {
                snprintf(err, sizeof err, "device %d declared twice", local);
                goto bad;
            }
        if (c->n_dev >= NET_MAX_CLIENT_DEVICES) {
            snprintf(err, sizeof err, "more than %d devices on one connection",
                     NET_MAX_CLIENT_DEVICES);
            goto bad;
        }
        char name[VV_INPUT_NAME_MAX] = "";
        for (int i = 3; i < nt; i++) {
            size_t len = strlen(name);
            snprintf(name + len, sizeof name - len, "%s%s", i > 3 ? " " : "", tok[i]);
        }
        int id;
        if (vv_input_device_add_driver(m, kind, name[0] ? name : NULL, "network", &id) != VV_OK) {
            snprintf(err, sizeof err, "%.150s", vv_error_message());
            vv_error_clear();
            goto bad;
        }
        c->local[c->n_dev] = local;
        c->id[c->n_dev++] = id;
        vv_input_raw_event ev;
        memset(&ev, 0, sizeof ev);
        ev.device = id;
        ev.time = now;
        ev.kind = VV_RAW_ADDED;
        vv_input_manager_feed(m, &ev);
        return;
    }
    vv_input_raw_event ev;
    if (vv_input_parse_event(tok, nt, &ev, err, sizeof err) != VV_OK)
        goto bad;
    int found = 0;
    for (int i = 0; i < c->n_dev; i++)
        if (c->local[i] == ev.device) {
            ev.device = c->id[i];
            found = 1;
            break;
        }
    if (!found) {
        snprintf(err, sizeof err, "device %d was not declared on this connection", ev.device);
        goto bad;
    }
    ev.time = now;
    if (vv_input_manager_feed(m, &ev) != VV_OK)
        vv_error_clear();
    return;
bad:
    vv_input_warn(m, "network: line %d: %s", c->line, err);
    reply(c->fd, "error line %d: %s\n", err, c->line);
}

static void
client_read(vv_input_manager *m, net_client *c, double now) {
    char buf[4096];
    ssize_t n = recv(c->fd, buf, sizeof buf, MSG_DONTWAIT);
    if (n == 0 || (n < 0 && errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR)) {
        client_drop(m, c, now);
        return;
    }
    for (ssize_t i = 0; i < n; i++) {
        char ch = buf[i];
        if (ch == '\n') {
            if (c->overflow) {
                c->line++;
                vv_input_warn(m, "network: line %d: longer than %d characters, dropped", c->line,
                              VV_INPUT_LINE_MAX);
                reply(c->fd, "error line %d: %s\n", "line too long", c->line);
            } else {
                c->buf[c->len] = '\0';
                client_line(m, c, c->buf, now);
                if (c->fd < 0)
                    return;
            }
            c->len = 0;
            c->overflow = 0;
        } else if (ch == '\0') {
            c->overflow = 1; /* binary garbage: drop the line */
        } else if (!c->overflow) {
            if (c->len >= VV_INPUT_LINE_MAX)
                c->overflow = 1;
            else
                c->buf[c->len++] = ch;
        }
    }
}

static void
net_ready(vv_input_manager *m, vv_input_driver *drv, int fd, double now) {
    net_server *s = drv->self;
    if (fd == s->lfd) {
        int cfd = accept(s->lfd, NULL, NULL);
        if (cfd < 0)
            return;
        fcntl(cfd, F_SETFL, fcntl(cfd, F_GETFL) | O_NONBLOCK);
        fcntl(cfd, F_SETFD, FD_CLOEXEC);
        for (int i = 0; i < NET_MAX_CLIENTS; i++)
            if (s->c[i].fd < 0) {
                memset(&s->c[i], 0, sizeof s->c[i]);
                s->c[i].fd = cfd;
                if (vv_input_watch(m, s->index, cfd) != VV_OK) {
                    vv_error_clear();
                    close(cfd);
                    s->c[i].fd = -1;
                }
                return;
            }
        vv_input_warn(m, "network: more than %d clients, connection refused", NET_MAX_CLIENTS);
        close(cfd);
        return;
    }
    for (int i = 0; i < NET_MAX_CLIENTS; i++)
        if (s->c[i].fd == fd) {
            client_read(m, &s->c[i], now);
            return;
        }
}

static void
net_close(vv_input_manager *m, vv_input_driver *drv) {
    net_server *s = drv->self;
    if (!s)
        return;
    for (int i = 0; i < NET_MAX_CLIENTS; i++)
        if (s->c[i].fd >= 0) {
            vv_input_unwatch(m, s->c[i].fd);
            close(s->c[i].fd);
        }
    vv_input_unwatch(m, s->lfd);
    close(s->lfd);
    unlink(s->path);
    free(s);
    drv->self = NULL;
}

vv_status
vv_input_manager_listen(vv_input_manager *m, const char *path) {
    if (!m || !path || !*path)
        return vv_error_set(VV_ERR_INVALID, "network: needs a socket path");
    if (m->listening)
        return vv_error_set(VV_ERR_INVALID, "network: already listening");
    struct sockaddr_un addr;
    memset(&addr, 0, sizeof addr);
    if (strlen(path) >= sizeof addr.sun_path)
        return vv_error_set(VV_ERR_INVALID, "network: %s: socket path longer than %zu bytes", path,
                            sizeof addr.sun_path - 1);
    addr.sun_family = AF_UNIX;
    memcpy(addr.sun_path, path, strlen(path) + 1);
    net_server *s = calloc(1, sizeof *s);
    if (!s)
        return vv_error_set(VV_ERR_NOMEM, "network: out of memory");
    for (int i = 0; i < NET_MAX_CLIENTS; i++)
        s->c[i].fd = -1;
    memcpy(s->path, addr.sun_path, sizeof s->path);
    s->lfd = socket(AF_UNIX, SOCK_STREAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
    if (s->lfd < 0) {
        free(s);
        return vv_error_set(VV_ERR_IO, "network: socket: %s", strerror(errno));
    }
    unlink(path); /* a stale socket from an earlier run */
    if (bind(s->lfd, (struct sockaddr *)&addr, sizeof addr) != 0 || listen(s->lfd, 8) != 0) {
        vv_status st = vv_error_set(VV_ERR_IO, "network: %s: %s", path, strerror(errno));
        close(s->lfd);
        free(s);
        return st;
    }
    vv_input_driver drv = {"network", s, net_ready, NULL, NULL, net_close};
    s->index = vv_input_driver_add(m, &drv);
    /* both set the message (no driver left, epoll); it names the socket */
    vv_status st = s->index < 0 ? VV_ERR_LIMIT : vv_input_watch(m, s->index, s->lfd);
    if (st != VV_OK) {
        if (s->index >= 0)
            m->n_drivers--;
        close(s->lfd);
        unlink(path);
        free(s);
        return vv_error_prefix(st, "network: %s", path);
    }
    m->listening = 1;
    return VV_OK;
}

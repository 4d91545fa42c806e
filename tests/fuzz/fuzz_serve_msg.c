/*
 * libFuzzer harness: the messages a browser client sends to `volvis serve`
 * (apps/volvis/serve/serve_msg.c, docs/serve-protocol.md). Each input is
 * one WebSocket text message: srv_msg_parse must accept it with every
 * field in range or refuse it with one printable line; a path it names is
 * then resolved inside a root folder of the harness (with a link out of
 * it), and must stay inside or be refused with one printable line; a URL
 * it names is put in normal form (idempotent, no user information, no
 * "." or ".." segment) and checked against a prefix.
 */
#include <limits.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "../../apps/volvis/serve/serve.h"
#include "fuzz_util.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static char root[PATH_MAX];

static void
one_line(const char *why) {
    if (!why[0])
        __builtin_trap();
    for (const char *p = why; *p; p++)
        if ((unsigned char)*p < 0x20)
            __builtin_trap();
}

static void
make_root(void) {
    const char *f = fuzz_write("root.probe", (const uint8_t *)"", 0);
    char dir[PATH_MAX];
    snprintf(dir, sizeof dir, "%s", f);
    *strrchr(dir, '/') = '\0';
    char p[PATH_MAX + 32];
    snprintf(p, sizeof p, "%s/root", dir);
    mkdir(p, 0755);
    if (!realpath(p, root))
        abort();
    snprintf(p, sizeof p, "%s/sub", root);
    mkdir(p, 0755);
    snprintf(p, sizeof p, "%s/a.json", root);
    FILE *fp = fopen(p, "w");
    if (fp)
        fclose(fp);
    snprintf(p, sizeof p, "%s/out", root);
    if (symlink("/", p) != 0 && access(p, F_OK) != 0)
        abort();
}

int
LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    if (!root[0])
        make_root();
    srv_msg m;
    char why[512];
    why[0] = '\0';
    if (srv_msg_parse((const char *)data, size, &m, why, sizeof why) != 0) {
        one_line(why);
        return 0;
    }
    if (m.width < 0 || m.height < 0 || m.width > SRV_VIEW_MAX || m.height > SRV_VIEW_MAX)
        __builtin_trap();
    if (m.type == SRV_LIST || m.type == SRV_OPEN || m.type == SRV_SAVE) {
        char full[PATH_MAX];
        for (int kind = 0; kind < 3; kind++) {
            why[0] = '\0';
            if (srv_path_resolve(root, m.path, kind, full, sizeof full, why, sizeof why) != 0) {
                one_line(why);
                continue;
            }
            size_t n = strlen(root);
            if (strncmp(full, root, n) != 0 || (full[n] != '\0' && full[n] != '/'))
                __builtin_trap(); /* out of the root */
        }
    }
    if (m.type == SRV_OPEN && m.url[0]) {
        /* a URL: refused in one line, or a normal form that is its own normal form, has
         * no user information, no "." or ".." segment, and is allowed only under the
         * prefix on a segment boundary */
        char norm[SRV_URL_MAX], again[SRV_URL_MAX];
        why[0] = '\0';
        if (srv_url_normalize(m.url, norm, sizeof norm, why, sizeof why) != 0) {
            one_line(why);
            return 0;
        }
        if (srv_url_normalize(norm, again, sizeof again, why, sizeof why) != 0 ||
            strcmp(norm, again) != 0)
            __builtin_trap();
        const char *auth = strstr(norm, "://") + 3;
        size_t al = strcspn(auth, "/");
        char path[SRV_URL_MAX]; /* the path, with a "/" after it (the query may hold anything) */
        snprintf(path, sizeof path, "%.*s/", (int)strcspn(auth + al, "?"), auth + al);
        size_t pl = strlen(path);
        if (memchr(auth, '@', al) || path[0] != '/' || strstr(path, "/../") || strstr(path, "/./"))
            __builtin_trap();
        /* no empty segment but the last (a trailing "/"): "//" only as the path's end */
        const char *dbl = strstr(path, "//");
        if (dbl && dbl != path + pl - 2)
            __builtin_trap();
        char *prefixes[] = {"http://h/data/"};
        if (srv_url_allowed(norm, NULL, 0, prefixes, 1) &&
            (strncmp(norm, "http://h/data/", 14) != 0 || strchr(norm, '?')))
            __builtin_trap();
    }
    return 0;
}

/*
 * The reader's side of the sandbox (include/volvis/sys/sandbox.h,
 * vv_sandbox_serve): what volvis-reader runs. It says hello, takes the
 * parent's request from descriptor 3, locks itself down (policy.c), runs
 * the program's handler for the request -- which calls the format row's
 * read directly -- and sends the result in a sealed memfd (payload.c), or
 * a volume's address for the parent to copy from (peek), or the error
 * trace as text, then ends; a store's reader serves chunks
 * until the parent closes its end. A test may ask it to misbehave after
 * the lockdown, as a hostile parser would (VOLVIS_SANDBOX_INJECT, carried
 * in the request).
 */
#define _GNU_SOURCE
#include <errno.h>
#include <fcntl.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <sys/prctl.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <unistd.h>

#include "core/internal.h"
#include "sandbox/sandbox_internal.h"

extern char **environ;

const char *const sbx_inject_names[SBX_N_INJECT] = {"",      "abort",  "segv",   "open",
                                                    "write", "socket", "execve", "fork",
                                                    "loop",  "oom",    "reply",  "scribble"};

/* The reader's state: its request, and the row it announced. */
struct vv_sandbox_server {
    const sbx_request *rq;
    int inject;
    int peek; /* a volume left in this process's memory for the parent to copy */
    int announced;
    char name[VV_SANDBOX_NAME_MAX], title[64];
};

/* What a broken or hostile parser would do, for the tests. */
static void
misbehave(int what) {
    switch (what) {
    case INJECT_ABORT:
        abort();
    case INJECT_SEGV: {
        volatile int *volatile wild = NULL;
        *wild = 1;
        break;
    }
    case INJECT_OPEN: {
        int fd = open("/etc/passwd", O_RDONLY | O_CLOEXEC);
        if (fd >= 0) {
            close(fd);
            vv_error_set(VV_ERR_IO, "injected: /etc/passwd could be opened");
        } else {
            int e = errno;
            vv_error_set(VV_ERR_IO, "injected: cannot open /etc/passwd: %s", strerror(e));
        }
        break;
    }
    case INJECT_WRITE: {
        int fd = open("volvis-sandbox-escape", O_WRONLY | O_CREAT | O_CLOEXEC, 0600);
        if (fd >= 0)
            close(fd);
        break;
    }
    case INJECT_SOCKET: {
        int fd = socket(AF_INET, SOCK_STREAM, 0);
        if (fd >= 0)
            close(fd);
        break;
    }
    case INJECT_EXEC: {
        char *args[] = {(char *)"/bin/true", NULL};
        execve(args[0], args, environ);
        break;
    }
    case INJECT_FORK: {
        pid_t p = fork();
        if (p == 0)
            _exit(0);
        break;
    }
    case INJECT_LOOP:
        for (volatile unsigned long i = 0;; i++)
            ;
    case INJECT_OOM:
        for (;;) {
            char *p = malloc((size_t)64 << 20);
            if (!p)
                abort();
            memset(p, 1, (size_t)64 << 20);
        }
    case INJECT_REPLY: {
        const uint32_t half[2] = {SBX_MAGIC, SBX_RESULT};
        while (send(SBX_FD, half, sizeof half, MSG_NOSIGNAL) < 0 && errno == EINTR)
            ;
        for (volatile unsigned long i = 0;; i++) /* the parent stops it */
            ;
    }
    default:
        break;
    }
}

static void
send_reply(const void *msg, size_t len, int fd_to_pass) {
    struct iovec io = {(void *)msg, len};
    union {
        struct cmsghdr h;
        char buf[CMSG_SPACE(sizeof(int))];
    } u;
    struct msghdr m = {0};
    m.msg_iov = &io;
    m.msg_iovlen = 1;
    if (fd_to_pass >= 0) {
        memset(&u, 0, sizeof u);
        m.msg_control = u.buf;
        m.msg_controllen = sizeof u.buf;
        struct cmsghdr *c = CMSG_FIRSTHDR(&m);
        c->cmsg_level = SOL_SOCKET;
        c->cmsg_type = SCM_RIGHTS;
        c->cmsg_len = CMSG_LEN(sizeof(int));
        memcpy(CMSG_DATA(c), &fd_to_pass, sizeof(int));
    }
    while (sendmsg(SBX_FD, &m, MSG_NOSIGNAL) < 0 && errno == EINTR)
        ;
}

static void
send_message(const sbx_reply *r, int fd_to_pass) {
    send_reply(r, offsetof(sbx_reply, err) + r->err_len, fd_to_pass);
}

void
vv_sandbox_announce(vv_sandbox_server *srv, const char *name, const char *title) {
    if (srv->announced)
        return;
    srv->announced = 1;
    snprintf(srv->name, sizeof srv->name, "%s", name ? name : "");
    snprintf(srv->title, sizeof srv->title, "%s", title ? title : "");
    static sbx_reply fr; /* zeroes, then the names */
    fr.magic = SBX_MAGIC;
    fr.kind = SBX_FORMAT;
    memcpy(fr.format, srv->name, sizeof fr.format);
    memcpy(fr.title, srv->title, sizeof fr.title);
    send_message(&fr, -1);
    if (srv->inject > INJECT_NONE && srv->inject < SBX_N_INJECT)
        misbehave(srv->inject);
}

/* The reader's last message: @p r with status @p s (and the error trace
 * when it failed) and @p fd, the memfd of the result; then it exits. */
static _Noreturn void
finish(vv_sandbox_server *srv, sbx_reply *r, vv_status s, int fd) {
    r->status = s;
    snprintf(r->format, sizeof r->format, "%s", srv->name);
    if (s != VV_OK) {
        r->err_len = (uint32_t)snprintf(r->err, sizeof r->err, "%s", vv_error_message());
        if (r->err_len >= sizeof r->err)
            r->err_len = sizeof r->err - 1;
    }
    unsigned char *mine = MAP_FAILED;
    if (srv->inject == INJECT_SCRIBBLE && s == VV_OK && r->bytes)
        mine = mmap(NULL, (size_t)r->bytes, PROT_READ | PROT_WRITE, MAP_SHARED, fd, 0);
    send_message(r, s == VV_OK ? fd : -1);
    if (mine != MAP_FAILED)
        for (unsigned char v = 0;; v++) /* the parent must stop it first */
            memset(mine, v, (size_t)r->bytes);
    /* voxels the parent copies out of this process: alive until it has
     * (it closes its end, or stops this process) */
    for (char c; srv->peek && s == VV_OK;) {
        const ssize_t k = recv(SBX_FD, &c, 1, 0);
        if (k == 0 || (k < 0 && errno != EINTR))
            break;
    }
    _exit(0);
}

/* One reply of the store server (status @p s, its error text when it
 * failed, @p fd handed over and closed). */
static void
box_reply(vv_sandbox_server *srv, sbx_reply *r, vv_status s, int fd) {
    (void)srv;
    r->kind = SBX_RESULT;
    r->status = s;
    r->err_len = 0;
    if (s != VV_OK) {
        r->err_len = (uint32_t)snprintf(r->err, sizeof r->err, "%s", vv_error_message());
        if (r->err_len >= sizeof r->err)
            r->err_len = sizeof r->err - 1;
    }
    send_message(r, s == VV_OK ? fd : -1);
    if (fd >= 0)
        close(fd);
}

/* The reader's answer to a store: the store's table (an sbx_store_head at
 * the start of the reader's window, a memfd sealed against shrinking and
 * growing, handed over once), then one chunk's voxels in the window for
 * each sbx_box until the parent closes its end. */
static _Noreturn void
serve_store(vv_sandbox_server *srv, const vv_sandbox_handler *h, sbx_reply *r) {
    const sbx_request *rq = srv->rq;
    vv_store st;
    memset(&st, 0, sizeof st);
    size_t info_len = 0;
    vv_status s = !h->store ? vv_error_set(VV_ERR_UNSUPPORTED, "this reader opens no stores")
                  : srv->inject == INJECT_OPEN ? (vv_sandbox_announce(srv, rq->format, rq->format),
                                                  vv_error_set(VV_ERR_IO, "cannot open it"))
                                               : h->store(srv, rq->format, rq->path, rq->args,
                                                          rq->args_len, &st, r->info, &info_len);
    vv_sandbox_announce(srv, rq->format, rq->format);
    static sbx_store_head head;
    uint64_t wbytes = 0;
    if (s == VV_OK) {
        r->info_len = (uint32_t)(info_len <= VV_SANDBOX_INFO_MAX ? info_len : 0);
        head.n_levels = st.n_levels;
        head.n_channels = st.n_channels;
        head.n_times = st.n_times;
        head.has_range = st.has_range;
        memcpy(head.range, st.range, sizeof head.range);
        for (int l = 0; l < st.n_levels && l < VV_STORE_MAX_LEVELS; l++) {
            const vv_volume *v = st.lv[l].hdr;
            memcpy(head.lv[l].dims, v->dims, sizeof head.lv[l].dims);
            memcpy(head.lv[l].cdims, st.lv[l].cdims, sizeof head.lv[l].cdims);
            head.lv[l].type = v->type;
            head.lv[l].unit = v->unit;
            memcpy(head.lv[l].spacing, v->spacing, sizeof head.lv[l].spacing);
            memcpy(head.lv[l].origin, v->origin, sizeof head.lv[l].origin);
            memcpy(head.lv[l].direction, v->direction, sizeof head.lv[l].direction);
        }
        if (st.n_levels < 1 || st.n_levels > VV_STORE_MAX_LEVELS)
            s = vv_error_set(VV_ERR_LIMIT, "%d levels (1 .. %d are read)", st.n_levels,
                             VV_STORE_MAX_LEVELS);
        else if (!(wbytes = sbx_window_bytes(&head)))
            s = vv_error_set(VV_ERR_LIMIT, "chunks of over %llu bytes",
                             (unsigned long long)SBX_MAX_BOX_BYTES);
    }
    int fd = -1;
    unsigned char *win = MAP_FAILED;
    if (s == VV_OK) {
        r->bytes = wbytes;
        fd = memfd_create("volvis-window", MFD_CLOEXEC | MFD_ALLOW_SEALING);
        if (fd >= 0 && ftruncate(fd, (off_t)wbytes) == 0 &&
            fcntl(fd, F_ADD_SEALS, F_SEAL_SHRINK | F_SEAL_GROW | F_SEAL_SEAL) == 0)
            win = mmap(NULL, (size_t)wbytes, PROT_READ | PROT_WRITE, MAP_SHARED, fd, 0);
        if (win == MAP_FAILED) {
            if (fd >= 0)
                close(fd);
            fd = -1;
            s = vv_error_set(VV_ERR_NOMEM, "the reader could not make its window of %llu bytes",
                             (unsigned long long)wbytes);
        } else {
            memcpy(win, &head, sizeof head);
        }
    }
    box_reply(srv, r, s, fd);
    unsigned char *scratch = s == VV_OK && st.scratch ? malloc(st.scratch) : NULL;
    if (s != VV_OK || (st.scratch && !scratch))
        _exit(0);
    for (;;) {
        sbx_box q;
        ssize_t n;
        while ((n = recv(SBX_FD, &q, sizeof q, 0)) < 0 && errno == EINTR)
            ;
        if (n == 0)
            _exit(0); /* the parent is done */
        if (n != (ssize_t)sizeof q || q.magic != SBX_MAGIC)
            _exit(2);
        int ok = q.level >= 0 && q.level < st.n_levels, org[3] = {0, 0, 0}, dims[3] = {0, 0, 0};
        uint64_t bytes = ok ? vv_voxel_type_size(st.lv[q.level].hdr->type) : 0;
        for (int k = 0; k < 3 && ok; k++) {
            const int cd = st.lv[q.level].cdims[k], d = st.lv[q.level].hdr->dims[k];
            ok = q.c[k] >= 0 && q.c[k] <= (d - 1) / cd;
            org[k] = ok ? q.c[k] * cd : 0;
            dims[k] = ok ? (org[k] + cd > d ? d : org[k] + cd) - org[k] : 0;
            bytes *= (uint64_t)dims[k];
        }
        memset(r, 0, offsetof(sbx_reply, err));
        r->magic = SBX_MAGIC;
        snprintf(r->format, sizeof r->format, "%s", srv->name);
        r->bytes = bytes;
        int missing = 0;
        uint64_t file_bytes = 0;
        if (!ok || bytes == 0 || bytes > wbytes)
            s = vv_error_set(VV_ERR_INVALID, "chunk (%d, %d, %d) of level %d asked: not in it",
                             q.c[0], q.c[1], q.c[2], q.level);
        else
            s = st.read_chunk(st.ctx, q.level, q.c, scratch, win, org, dims, &missing, &file_bytes);
        r->missing = missing;
        r->file_bytes = file_bytes;
        box_reply(srv, r, s, -1);
    }
}

/* Runs the handler of a one-shot request and ends with its result. */
static _Noreturn void
serve_one(vv_sandbox_server *srv, const vv_sandbox_handler *h, sbx_reply *r) {
    const sbx_request *rq = srv->rq;
    vv_status s = VV_OK;
    int fd = -1;
    if (srv->inject == INJECT_OPEN) {
        vv_sandbox_announce(srv, rq->format, rq->format);
        finish(srv, r, VV_ERR_IO, -1);
    }
    if (rq->op == VV_SANDBOX_VOLUME && h->volume) {
        vv_volume *v = NULL;
        size_t info_len = 0;
        s = h->volume(srv, rq->format, rq->path, rq->args, rq->args_len, &v, r->info, &info_len);
        if (s == VV_OK) {
            r->info_len = (uint32_t)(info_len <= VV_SANDBOX_INFO_MAX ? info_len : 0);
            memcpy(r->dims, v->dims, sizeof r->dims);
            r->type = v->type;
            memcpy(r->spacing, v->spacing, sizeof r->spacing);
            memcpy(r->origin, v->origin, sizeof r->origin);
            memcpy(r->direction, v->direction, sizeof r->direction);
            r->unit = v->unit;
            r->data_origin = v->data_origin;
            r->modification = v->modification;
            r->space = v->space;
            r->bytes = vv_volume_voxel_count(v) * vv_voxel_type_size(v->type);
            if (srv->peek) /* the parent copies them from here */
                r->addr = (uint64_t)(uintptr_t)v->data;
            else if ((fd = sbx_sealed(sbx_memfd_of(v->data, (size_t)r->bytes),
                                      srv->inject == INJECT_SCRIBBLE)) < 0)
                s = vv_error_set(VV_ERR_NOMEM,
                                 "the reader could not hand over %llu bytes of voxels",
                                 (unsigned long long)r->bytes);
        }
    } else if (rq->op == VV_SANDBOX_LIST && h->list) {
        void *blob = NULL;
        size_t len = 0;
        s = h->list(srv, rq->format, rq->path, rq->args, rq->args_len, &blob, &len);
        if (s == VV_OK) {
            r->bytes = len;
            if (!len || (fd = sbx_sealed(sbx_memfd_of(blob, len), 0)) < 0) /* a copy */
                s = vv_error_set(VV_ERR_NOMEM, "the reader could not hand over its listing");
        }
        free(blob);
    } else if (rq->op == VV_SANDBOX_MESH && h->mesh) {
        vv_mesh *m = NULL;
        s = h->mesh(srv, rq->format, rq->path, &m);
        if (s == VV_OK) {
            r->n_vertices = m->n_vertices;
            r->n_triangles = m->n_triangles;
            if ((fd = sbx_sealed(sbx_mesh_memfd(m, &r->bytes), 0)) < 0)
                s = vv_error_set(VV_ERR_NOMEM, "the reader could not hand over the mesh");
        }
        vv_mesh_free(m);
    } else if (rq->op == VV_SANDBOX_GRID && h->grid) {
        vv_grid *g = NULL;
        s = h->grid(srv, rq->format, rq->path, &g);
        if (s == VV_OK && (fd = sbx_sealed(sbx_grid_memfd(g, &r->bytes), 0)) < 0)
            s = vv_error_set(VV_ERR_NOMEM, "the reader could not hand over the grid");
        vv_grid_free(g);
    } else {
        s = vv_error_set(VV_ERR_UNSUPPORTED, "this reader does not serve op %d", rq->op);
    }
    vv_sandbox_announce(srv, rq->format, rq->format); /* a handler that failed before */
    finish(srv, r, s, fd);
}

int
vv_sandbox_serve(int argc, char **argv, const vv_sandbox_handler *h) {
    (void)argc;
    (void)argv;
    if (fcntl(SBX_FD, F_GETFD) < 0) {
        fprintf(stderr, "volvis-reader: started by VolVis's loader only (it reads its request "
                        "from descriptor 3)\n");
        return 2;
    }
    /* who we are first, in a layout no protocol changes */
    const sbx_hello hello = {SBX_MAGIC, SBX_HELLO, VV_SANDBOX_PROTOCOL, sbx_layout()};
    send_reply(&hello, sizeof hello, -1);
    static sbx_request rq;
    ssize_t n;
    while ((n = recv(SBX_FD, &rq, sizeof rq, 0)) < 0 && errno == EINTR)
        ;
    /* a spare reader whose program ended: nothing to do (ECONNRESET: it
     * ended without reading the hello) */
    if (n == 0 || (n < 0 && (errno == ECONNRESET || errno == EPIPE)))
        _exit(0);
    if (n != (ssize_t)sizeof rq || rq.magic != SBX_MAGIC || rq.version != VV_SANDBOX_PROTOCOL ||
        rq.path_len == 0 || rq.path_len >= SBX_MAX_PATH || rq.args_len > VV_SANDBOX_ARGS_MAX ||
        !memchr(rq.format, 0, sizeof rq.format)) {
        fprintf(stderr, "volvis-reader: malformed request on descriptor 3\n");
        return 2;
    }
    rq.path[rq.path_len] = '\0';
    vv_sandbox_server srv;
    memset(&srv, 0, sizeof srv);
    srv.rq = &rq;
    srv.inject = rq.inject > INJECT_NONE && rq.inject < SBX_N_INJECT ? rq.inject : INJECT_NONE;
    srv.peek = rq.peek == 1 && rq.op == VV_SANDBOX_VOLUME;
    static sbx_reply r;
    r.magic = SBX_MAGIC;
    r.kind = SBX_RESULT;

    vv_memory_budget_set(rq.budget);
    vv_threads_set(rq.threads);
    sbx_set_limits(rq.budget, rq.threads, rq.cpu_seconds, srv.peek);
    sbx_profile_before_lockdown();
    if (prctl(PR_SET_NO_NEW_PRIVS, 1, 0, 0, 0) != 0 ||
        (sbx_landlock_restrict(rq.path) != 0 && errno != ENOSYS && errno != EOPNOTSUPP) ||
        sbx_seccomp_restrict() != 0) {
        int e = errno;
        finish(&srv, &r,
               vv_error_set(VV_ERR_UNSUPPORTED, "the reader sandbox could not be set up (%s)",
                            strerror(e)),
               -1);
    }
    /* from here on, what the file makes the parser do stays in here;
     * voxels are made in memfds to be handed over, or, when the parent
     * copies them out (peek), in ordinary memory (huge pages, no memfd's
     * page-by-page shared memory) */
    if (!srv.peek)
        vv_volume_set_allocator(sbx_memfd_alloc, sbx_memfd_release);
    if (rq.op == VV_SANDBOX_STORE)
        serve_store(&srv, h, &r);
    serve_one(&srv, h, &r);
}

/*
 * The parent's side of the sandbox (include/volvis/sys/sandbox.h): finding
 * this library's own reader, starting it (one kept ahead, process-wide),
 * checking that it speaks this protocol, one call (vv_sandbox_call_reader)
 * and turning whatever the reader does into its result or one error line.
 */
#define _GNU_SOURCE
#include <dirent.h>
#include <dlfcn.h>
#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <link.h>
#include <poll.h>
#include <pthread.h>
#include <signal.h>
#include <spawn.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/uio.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "core/internal.h"
#include "sandbox/sandbox_internal.h"

extern char **environ;

double
sbx_now(void) {
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

/* Seconds a reader may run: 60 plus one per 10 MB of input (a folder's
 * files counted), or $VOLVIS_SANDBOX_TIMEOUT. */
unsigned
sbx_time_limit(const char *path) {
    const char *e = getenv("VOLVIS_SANDBOX_TIMEOUT");
    if (e && *e) {
        char *end;
        long t = strtol(e, &end, 10);
        if (*end == '\0' && t >= 1 && t <= 86400)
            return (unsigned)t;
    }
    struct stat st;
    uint64_t size = 0;
    int there = stat(path, &st) == 0;
    if (there && S_ISREG(st.st_mode)) {
        size = (uint64_t)st.st_size;
    } else if (there && S_ISDIR(st.st_mode)) { /* a series or a stack: its files */
        DIR *d = opendir(path);
        struct dirent *ent;
        while (d && (ent = readdir(d)))
            if (fstatat(dirfd(d), ent->d_name, &st, 0) == 0 && S_ISREG(st.st_mode))
                size += (uint64_t)st.st_size;
        if (d)
            closedir(d);
    }
    uint64_t t = 60 + size / 10000000u;
    return t > 86400 ? 86400u : (unsigned)t;
}

/* The one line for a reader that ended without a result. */
vv_status
sbx_describe_end(int status, uint64_t peak, uint64_t budget, const char *fmt_name,
                 const char *title, const char *file, unsigned limit, int timed_out) {
    if (timed_out)
        return vv_error_set(VV_ERR_LIMIT, "%s: %s: the %s reader took more than %u s; stopped",
                            fmt_name, file, title, limit);
    if (WIFSIGNALED(status)) {
        int sig = WTERMSIG(status);
        const char *abbrev = sigabbrev_np(sig);
        char name[32];
        snprintf(name, sizeof name, "SIG%s", abbrev ? abbrev : "?");
        if (sig == SIGSYS)
            return vv_error_set(VV_ERR_FORMAT,
                                "%s: %s: the %s reader made a system call the sandbox forbids "
                                "(SIGSYS) and was stopped; the file is hostile or the reader "
                                "broken",
                                fmt_name, file, title);
        if (sig == SIGXCPU)
            return vv_error_set(VV_ERR_LIMIT,
                                "%s: %s: the %s reader used more than %u s of CPU time; stopped",
                                fmt_name, file, title, limit);
        /* malloc failing at the address-space limit ends in abort() (or a
         * C++ bad_alloc that nobody catches): the peak tells it apart */
        if ((sig == SIGABRT || sig == SIGSEGV || sig == SIGKILL) && peak >= budget / 2)
            return vv_error_set(
                VV_ERR_LIMIT,
                "%s: %s: the %s reader ran out of memory (%s at a peak of %llu "
                "MiB; it may map %llu MiB); the file is malformed or too large",
                fmt_name, file, title, name, (unsigned long long)(peak >> 20),
                (unsigned long long)(sbx_address_limit(budget, vv_threads_get()) >> 20));
        if (sig == SIGKILL)
            return vv_error_set(VV_ERR_FORMAT,
                                "%s: %s: the %s reader was killed (SIGKILL; out of memory?)",
                                fmt_name, file, title);
        return vv_error_set(VV_ERR_FORMAT,
                            "%s: %s: the %s reader crashed (%s); the file is "
                            "malformed",
                            fmt_name, file, title, name);
    }
    return vv_error_set(VV_ERR_FORMAT, "%s: %s: the %s reader exited with status %d and no result",
                        fmt_name, file, title, WIFEXITED(status) ? WEXITSTATUS(status) : -1);
}

/* Starts volvis-reader with the parent's end of a new socket pair in
 * *@p sock. Returns 0 or an errno value. */
int
sbx_spawn_reader(const char *exe, pid_t *pid, int *sock) {
    int sv[2];
    if (socketpair(AF_UNIX, SOCK_SEQPACKET | SOCK_CLOEXEC, 0, sv) != 0)
        return errno;
    if (sv[1] == SBX_FD) { /* dup2 onto itself would keep close-on-exec */
        int d = fcntl(sv[1], F_DUPFD_CLOEXEC, SBX_FD + 1);
        close(sv[1]);
        sv[1] = d;
    }
    posix_spawn_file_actions_t fa;
    posix_spawnattr_t at;
    posix_spawn_file_actions_init(&fa);
    posix_spawn_file_actions_addopen(&fa, 0, "/dev/null", O_RDONLY, 0);
    posix_spawn_file_actions_addopen(&fa, 1, "/dev/null", O_WRONLY, 0);
    posix_spawn_file_actions_adddup2(&fa, sv[1], SBX_FD);
    posix_spawn_file_actions_addclosefrom_np(&fa, SBX_FD + 1);
    posix_spawnattr_init(&at);
    sigset_t none, all;
    sigemptyset(&none);
    sigfillset(&all);
    posix_spawnattr_setsigmask(&at, &none);
    posix_spawnattr_setsigdefault(&at, &all);
    posix_spawnattr_setflags(&at, POSIX_SPAWN_SETSIGMASK | POSIX_SPAWN_SETSIGDEF);
    char *args[] = {(char *)"volvis-reader", NULL};
    /* the environment, and glibc's malloc asking for transparent huge pages
     * (a fresh process faults in all it allocates; 4 KiB faults cost more
     * than the parser's work on a small file) */
    size_t ne = 0;
    while (environ[ne])
        ne++;
    char **env = calloc(ne + 3, sizeof *env);
    char *tunables = NULL;
    const char *old = getenv("GLIBC_TUNABLES");
    if (env && asprintf(&tunables, "GLIBC_TUNABLES=%s%sglibc.malloc.hugetlb=1", old ? old : "",
                        old && *old ? ":" : "") < 0)
        tunables = NULL;
    size_t k = 0;
    for (size_t i = 0; env && i < ne; i++)
        if (strncmp(environ[i], "GLIBC_TUNABLES=", 15) || !tunables)
            env[k++] = environ[i];
    if (env && tunables)
        env[k++] = tunables;
    /* its OpenMP threads sleep once their work is done, not spin: a
     * volume's reader lives on while this process copies its voxels out
     * (peek), and spinning threads would take the cores the copy runs on
     * (the caller's own OMP_WAIT_POLICY kept) */
    if (env && !getenv("OMP_WAIT_POLICY"))
        env[k++] = (char *)"OMP_WAIT_POLICY=PASSIVE";
    int err = sv[1] < 0 ? errno : posix_spawn(pid, exe, &fa, &at, args, env ? env : environ);
    free(tunables);
    free(env);
    posix_spawn_file_actions_destroy(&fa);
    posix_spawnattr_destroy(&at);
    if (sv[1] >= 0)
        close(sv[1]);
    if (err != 0) {
        close(sv[0]);
        return err;
    }
    *sock = sv[0];
    return 0;
}

/*
 * One reader started ahead of the next load (a reader's start, mostly
 * GDCM's dictionary and the dynamic linking, is about 50 ms): started
 * during each sandboxed read but a process's first, taken by the next one
 * when it is still alive,
 * of the same program and of this process (not inherited through fork).
 * It waits for its request unlocked and exits when this process closes its
 * end. Process-wide, under spare_lock. VOLVIS_SANDBOX_SPARE=0: none.
 */
static pthread_mutex_t spare_lock = PTHREAD_MUTEX_INITIALIZER;
static atomic_int loads_started;
static pid_t spare_pid, spare_owner;
static int spare_sock = -1;
static char spare_exe[PATH_MAX];

/* Readers killed after their result came, reaped later (their teardown,
 * unmapping a process, need not delay the load): under spare_lock. */
static pid_t dying[16];
static int n_dying;

/* Reaps what has ended of dying[] (all of it when @p block). Holds
 * spare_lock. */
static void
reap_dying(int block) {
    int k = 0;
    for (int i = 0; i < n_dying; i++) {
        pid_t r;
        while ((r = waitpid(dying[i], NULL, block ? 0 : WNOHANG)) < 0 && errno == EINTR)
            ;
        if (r == 0)
            dying[k++] = dying[i]; /* still ending */
    }
    n_dying = k;
}

void
sbx_reap_later(pid_t pid) {
    pthread_mutex_lock(&spare_lock);
    reap_dying(0);
    if (n_dying == (int)(sizeof dying / sizeof dying[0]))
        reap_dying(1);
    dying[n_dying++] = pid;
    pthread_mutex_unlock(&spare_lock);
}

int
sbx_take_reader(const char *exe, pid_t *pid, int *sock) {
    pthread_mutex_lock(&spare_lock);
    reap_dying(0);
    pid_t p = spare_pid;
    int fd = spare_sock, mine = spare_owner == getpid() && !strcmp(spare_exe, exe);
    spare_pid = 0;
    spare_sock = -1;
    pthread_mutex_unlock(&spare_lock);
    if (p > 0 && mine && waitpid(p, NULL, WNOHANG) == 0) {
        *pid = p;
        *sock = fd;
        return 0;
    }
    if (fd >= 0)
        close(fd); /* a dead spare, another program's, or a parent's */
    if (p > 0 && mine) {
        kill(p, SIGKILL);
        waitpid(p, NULL, 0);
    }
    return sbx_spawn_reader(exe, pid, sock);
}

static void
refill_spare(const char *exe) {
    const char *e = getenv("VOLVIS_SANDBOX_SPARE");
    if (e && !strcmp(e, "0"))
        return;
    pthread_mutex_lock(&spare_lock);
    if (spare_pid <= 0 || spare_owner != getpid()) {
        pid_t p;
        int fd;
        if (sbx_spawn_reader(exe, &p, &fd) == 0) {
            spare_pid = p;
            spare_sock = fd;
            spare_owner = getpid();
            snprintf(spare_exe, sizeof spare_exe, "%s", exe);
        }
    }
    pthread_mutex_unlock(&spare_lock);
}

/* The reader a volume load left to start after it (vv_sandbox_after_load):
 * its program, "" when none is owed. Under spare_lock. */
static char owed_exe[PATH_MAX];

static void
owe_spare(const char *exe) {
    pthread_mutex_lock(&spare_lock);
    snprintf(owed_exe, sizeof owed_exe, "%s", exe);
    pthread_mutex_unlock(&spare_lock);
}

void
vv_sandbox_after_load(void) {
    char exe[PATH_MAX];
    pthread_mutex_lock(&spare_lock);
    snprintf(exe, sizeof exe, "%s", owed_exe);
    owed_exe[0] = 0;
    pthread_mutex_unlock(&spare_lock);
    if (exe[0])
        refill_spare(exe);
}

void
vv_sandbox_release_spare(void) {
    pthread_mutex_lock(&spare_lock);
    reap_dying(1);
    if (spare_pid > 0 && spare_owner == getpid()) {
        close(spare_sock);
        kill(spare_pid, SIGKILL);
        waitpid(spare_pid, NULL, 0);
    }
    spare_pid = 0;
    spare_sock = -1;
    pthread_mutex_unlock(&spare_lock);
}

/* One message of a reader on @p sock into @p buf: its length; 0 when the
 * reader is gone, -1 when interrupted (try again), -2 when the message or
 * its control data was cut (malformed). *passed: the descriptor it carried
 * (-1: none; of several, the last, the others closed; closed when cut). */
ssize_t
sbx_recv(int sock, void *buf, size_t cap, int *passed) {
    union {
        struct cmsghdr h;
        char buf[CMSG_SPACE(sizeof(int))];
    } u;
    struct iovec io = {buf, cap};
    struct msghdr m = {0};
    m.msg_iov = &io;
    m.msg_iovlen = 1;
    m.msg_control = u.buf;
    m.msg_controllen = sizeof u.buf;
    *passed = -1;
    const ssize_t got = recvmsg(sock, &m, MSG_CMSG_CLOEXEC);
    if (got < 0 && errno == EINTR)
        return -1;
    if (got <= 0)
        return 0;
    for (struct cmsghdr *c = CMSG_FIRSTHDR(&m); c; c = CMSG_NXTHDR(&m, c))
        if (c->cmsg_level == SOL_SOCKET && c->cmsg_type == SCM_RIGHTS &&
            c->cmsg_len == CMSG_LEN(sizeof(int))) {
            if (*passed >= 0)
                close(*passed);
            memcpy(passed, CMSG_DATA(c), sizeof(int));
        }
    if (m.msg_flags & (MSG_TRUNC | MSG_CTRUNC)) {
        if (*passed >= 0)
            close(*passed);
        *passed = -1;
        return -2;
    }
    return got;
}

/* An object of the library's own code's file: dladdr names the file it was
 * loaded from (libvolvis.so, or the program the library is linked into). */
static const char reader_anchor = 0;

/* The file this code was loaded from: a shared object's path, or for the
 * main program (whose link map has the name "", and whose dladdr name is
 * argv[0], not a path when found through PATH) the program itself. */
static const char *
self_file(Dl_info *di) {
    struct link_map *map = NULL;
    if (!dladdr1(&reader_anchor, di, (void **)&map, RTLD_DL_LINKMAP))
        return NULL;
    if (!map || !map->l_name || !map->l_name[0])
        return "/proc/self/exe";
    return di->dli_fname;
}

/* The volvis-reader to start into @p buf (PATH_MAX bytes): $VOLVIS_READER,
 * else the one beside the object this code was loaded from (libvolvis.so,
 * or the program the library is linked into), else in ../libexec from
 * there, else the build tree's and the installed one compiled in. The
 * candidates tried go to @p tried when none is found. 1 when found. */
static int
reader_path(char *buf, size_t cap, char *tried, size_t tcap) {
    tried[0] = '\0';
    const char *e = getenv("VOLVIS_READER");
    if (e && *e) {
        snprintf(buf, cap, "%s", e);
        snprintf(tried, tcap, "VOLVIS_READER=%s", e);
        return access(buf, X_OK) == 0;
    }
    char cand[4][PATH_MAX];
    int n = 0;
    Dl_info di;
    const char *f;
    char *obj = NULL;
    if ((f = self_file(&di)) && (obj = realpath(f, NULL))) {
        char *slash = strrchr(obj, '/');
        if (slash && strlen(obj) + 32 < PATH_MAX) {
            *slash = '\0';
            snprintf(cand[n++], PATH_MAX, "%.*s/volvis-reader", PATH_MAX - 32, obj);
            snprintf(cand[n++], PATH_MAX, "%.*s/../libexec/volvis-reader", PATH_MAX - 32, obj);
        }
        free(obj);
    }
#ifdef VV_READER_BUILD_PATH
    snprintf(cand[n++], PATH_MAX, "%s", VV_READER_BUILD_PATH);
#endif
#ifdef VV_READER_INSTALL_PATH
    snprintf(cand[n++], PATH_MAX, "%s", VV_READER_INSTALL_PATH);
#endif
    size_t len = 0;
    for (int i = 0; i < n; i++) {
        const size_t l = strlen(cand[i]);
        if (l < cap && access(cand[i], X_OK) == 0) {
            memcpy(buf, cand[i], l + 1);
            return 1;
        }
        if (len < tcap)
            len += (size_t)snprintf(tried + len, tcap - len, "%s%s", i ? ", " : "", cand[i]);
    }
    return 0;
}

vv_status
sbx_reader_for(const char *name, const char *path, char *exe) {
    const char *file = vv_path_basename(path);
    if (strlen(path) >= SBX_MAX_PATH)
        return vv_error_set(VV_ERR_LIMIT, "%s: %s: a path of over %d bytes", name, file,
                            SBX_MAX_PATH - 1);
    char tried[2048];
    if (!reader_path(exe, PATH_MAX, tried, sizeof tried))
        return vv_error_set(VV_ERR_IO,
                            "%s: %s: the sandboxed reader volvis-reader was not found (tried %s; "
                            "set VOLVIS_READER to its path, or VOLVIS_SANDBOX=0 to read in this "
                            "process)",
                            name, file, tried);
    return VV_OK;
}

vv_status
sbx_hello_wait(int sock, double deadline, const char *exe, const char *name, const char *file) {
    for (;;) {
        const double left = deadline - sbx_now();
        if (left <= 0)
            return vv_error_set(VV_ERR_LIMIT, "%s: %s: the reader %s did not answer; stopped", name,
                                file, exe);
        struct pollfd pf = {sock, POLLIN, 0};
        int pr = poll(&pf, 1, (int)(left * 1000) + 1);
        if (pr < 0 && errno == EINTR)
            continue;
        if (pr <= 0)
            continue;
        sbx_hello h;
        int passed = -1;
        const ssize_t got = sbx_recv(sock, &h, sizeof h, &passed);
        if (passed >= 0)
            close(passed);
        if (got == -1)
            continue;
        if (got == (ssize_t)sizeof h && h.magic == SBX_MAGIC && h.kind == SBX_HELLO) {
            if (h.version == VV_SANDBOX_PROTOCOL && h.layout == sbx_layout())
                return VV_OK;
            if (h.version == VV_SANDBOX_PROTOCOL)
                return vv_error_set(VV_ERR_IO,
                                    "%s: %s: the reader %s speaks protocol %u with structures of "
                                    "another layout (another build's volvis-reader: set "
                                    "VOLVIS_READER to this build's)",
                                    name, file, exe, h.version);
            return vv_error_set(VV_ERR_IO,
                                "%s: %s: the reader %s speaks protocol %u, this library %d "
                                "(another build's volvis-reader: set VOLVIS_READER to this "
                                "build's)",
                                name, file, exe, h.version, VV_SANDBOX_PROTOCOL);
        }
        return vv_error_set(VV_ERR_IO,
                            "%s: %s: the reader %s does not speak protocol %d (another build's "
                            "volvis-reader: set VOLVIS_READER to this build's)",
                            name, file, exe, VV_SANDBOX_PROTOCOL);
    }
}

int
vv_sandbox_enabled(void) {
    const char *e = getenv("VOLVIS_SANDBOX");
    return !(e && !strcmp(e, "0"));
}

int
vv_sandbox_all(void) {
    const char *e = getenv("VOLVIS_SANDBOX");
    return e && !strcmp(e, "all");
}

int
sbx_can_peek(pid_t pid) {
    static atomic_int known = -1;
    const char *e = getenv("VOLVIS_SANDBOX_PEEK");
    if (e && !strcmp(e, "0"))
        return 0;
    int k = atomic_load(&known);
    if (k >= 0)
        return k;
    /* address 1 is never mapped (vm.mmap_min_addr): the read fails with
     * EFAULT once the access check has passed, EPERM when it did not */
    char c;
    struct iovec here = {&c, 1}, there = {(void *)(uintptr_t)1, 1};
    const ssize_t n = process_vm_readv(pid, &here, 1, &there, 1, 0);
    if (n < 0 && errno == ESRCH)
        return 0; /* gone: nothing learnt */
    k = n < 0 && errno == EFAULT;
    atomic_store(&known, k);
    return k;
}

sbx_request *
sbx_new_request(const vv_sandbox_call *c) {
    static sbx_request proto; /* zeroes for the request's padding */
    sbx_request *rq = malloc(sizeof *rq);
    if (!rq)
        return NULL;
    *rq = proto;
    rq->magic = SBX_MAGIC;
    rq->version = VV_SANDBOX_PROTOCOL;
    rq->op = (int32_t)c->op;
    snprintf(rq->format, sizeof rq->format, "%s", c->format ? c->format : "");
    rq->budget = vv_memory_budget_get();
    rq->threads = vv_threads_get();
    rq->cpu_seconds = sbx_time_limit(c->path);
    rq->args_len = (uint32_t)(c->args_len <= VV_SANDBOX_ARGS_MAX ? c->args_len : 0);
    if (rq->args_len)
        memcpy(rq->args, c->args, rq->args_len);
    rq->path_len = (uint32_t)strlen(c->path);
    memcpy(rq->path, c->path, rq->path_len);
    const char *inj = getenv("VOLVIS_SANDBOX_INJECT");
    for (int i = 1; inj && i < SBX_N_INJECT; i++)
        if (!strcmp(inj, sbx_inject_names[i]))
            rq->inject = i;
    return rq;
}

void
vv_sandbox_result_clear(vv_sandbox_result *r) {
    if (!r)
        return;
    vv_volume_free(r->volume);
    vv_mesh_free(r->mesh);
    vv_grid_free(r->grid);
    free(r->blob);
    memset(r, 0, sizeof *r);
}

vv_status
vv_sandbox_call_reader(const vv_sandbox_call *c, vv_sandbox_result *ans) {
    memset(ans, 0, sizeof *ans);
    if (!c || !c->path || c->args_len > VV_SANDBOX_ARGS_MAX ||
        (c->format && strlen(c->format) >= VV_SANDBOX_NAME_MAX))
        return vv_error_set(VV_ERR_INVALID, "sandbox: a bad call");
    const char *path = c->path, *file = vv_path_basename(path);
    const int op = c->op;
    /* the row's names until the reader names the one it reads with */
    char name[VV_SANDBOX_NAME_MAX], title[64];
    snprintf(name, sizeof name, "%s", c->name ? c->name : "load");
    snprintf(title, sizeof title, "%s", c->title ? c->title : "file");
    char exe[PATH_MAX];
    vv_status s0 = sbx_reader_for(name, path, exe);
    if (s0 != VV_OK)
        return s0;
    sbx_request *rq = sbx_new_request(c);
    if (!rq)
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    uint64_t rq_budget = rq->budget;
    unsigned limit = rq->cpu_seconds;

    pid_t pid = -1;
    int sock = -1;
    int err = sbx_take_reader(exe, &pid, &sock);
    if (err != 0) {
        free(rq);
        return vv_error_set(VV_ERR_IO, "%s: %s: cannot start %s: %s", name, file, exe,
                            strerror(err));
    }
    /* a volume's voxels copied straight out of the reader's memory where
     * this process may (no memfd's shared pages: the reader decodes into
     * huge pages); an injected misbehaviour keeps the memfd it tests */
    const int peek = op == VV_SANDBOX_VOLUME && !rq->inject && sbx_can_peek(pid);
    rq->peek = peek;
    ssize_t n;
    while ((n = send(sock, rq, sizeof *rq, MSG_NOSIGNAL)) < 0 && errno == EINTR)
        ;
    free(rq);
    /* a process's second load and later ones start the next reader (most
     * programs that load once never load again: the CLI's spare would only
     * take a core): a volume's once its load is done with the voxels
     * (vv_sandbox_after_load), where it takes no core from the read; the
     * other ops' while this one reads */
    if (atomic_fetch_add(&loads_started, 1) > 0) {
        if (op == VV_SANDBOX_VOLUME)
            owe_spare(exe);
        else
            refill_spare(exe);
    }

    sbx_reply *r = malloc(sizeof *r);
    int result = 0, timed_out = 0, malformed = 0, status = 0;
    double deadline = sbx_now() + limit + 5;
    /* the reader's protocol first (its hello was sent before our request) */
    vv_status s = sbx_hello_wait(sock, deadline, exe, name, file);
    if (s != VV_OK) {
        close(sock);
        kill(pid, SIGKILL);
        while (waitpid(pid, NULL, 0) < 0 && errno == EINTR)
            ;
        free(r);
        return s;
    }
    while (r && !result && !malformed && n >= 0) {
        double left = deadline - sbx_now();
        if (left <= 0) {
            timed_out = 1;
            break;
        }
        struct pollfd pf = {sock, POLLIN, 0};
        int pr = poll(&pf, 1, (int)(left * 1000) + 1);
        if (pr < 0 && errno == EINTR)
            continue;
        if (pr <= 0)
            continue;
        int passed = -1;
        const ssize_t got = sbx_recv(sock, r, sizeof *r, &passed);
        if (got == -1)
            continue;
        if (got == 0)
            break; /* the child is gone */
        if (got < 0) {
            malformed = 1;
            break;
        }
        int k = sbx_take_message_peer(op, r, (size_t)got, passed, peek ? pid : 0, name, title, file,
                                      ans, &s);
        result = k > 0;
        malformed = k < 0 || (k == 0 && passed >= 0); /* a memfd before the result */
    }
    close(sock);
    /* with its result sent the child has nothing left to do (reaped
     * later); without one it is stopped and its end described */
    uint64_t peak = 0;
    kill(pid, SIGKILL);
    if (result) {
        sbx_reap_later(pid);
    } else {
        struct rusage ru;
        memset(&ru, 0, sizeof ru);
        while (wait4(pid, &status, 0, &ru) < 0 && errno == EINTR)
            ;
        peak = (uint64_t)ru.ru_maxrss * 1024u;
    }
    const char *fmt_name = name;
    if (!r) {
        s = vv_error_set(VV_ERR_NOMEM, "out of memory");
    } else if (malformed) {
        s = vv_error_set(VV_ERR_FORMAT,
                         "%s: %s: the %s reader sent a malformed reply and was stopped; the "
                         "file is hostile or the reader broken",
                         fmt_name, file, title);
    } else if (!result) {
        s = sbx_describe_end(status, peak, rq_budget, fmt_name, title, file, limit, timed_out);
    }
    free(r);
    return s;
}

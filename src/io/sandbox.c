/*
 * The reader sandbox (src/io/sandbox.h; docs/security.md, "The reader
 * sandbox"). Both sides live here: the parent, which starts volvis-reader
 * and turns whatever it does into a volume or one error, and the child's
 * main function, which locks itself down before it touches the file.
 *
 * The protocol, over a SOCK_SEQPACKET socket pair on the child's descriptor
 * 3 (each message whole or not at all): the parent sends one sbx_request;
 * the child answers with an sbx_reply of kind SBX_FORMAT once it knows the
 * format (so that a crash can be named after its reader) and one of kind
 * SBX_RESULT, which carries the memfd of the voxels (SCM_RIGHTS) when the
 * read succeeded. The parent trusts nothing in a reply: sizes are checked
 * against the memfd, the memfd must be sealed against shrinking, geometry
 * must be finite, and the value range is computed again.
 */
#define _GNU_SOURCE
#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <linux/landlock.h>
#include <math.h>
#include <poll.h>
#include <pthread.h>
#include <seccomp.h>
#include <signal.h>
#include <spawn.h>
#include <stdatomic.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/file.h>
#include <sys/mman.h>
#include <sys/prctl.h>
#include <sys/resource.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/syscall.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "core/internal.h"
#include "io/sandbox.h"
#include "volvis/bricks.h"

extern char **environ;

#define SBX_VERSION 5
#define SBX_FD 3
#define SBX_MAX_PATH 4096
#define SBX_MAX_SERIES 200000 /* as many as the files a listing reads */

/* Test-only misbehaviour of the child (VOLVIS_SANDBOX_INJECT), after it is
 * locked down: what a hostile or broken parser would do. */
enum sbx_inject {
    INJECT_NONE,
    INJECT_ABORT,   /* abort(): a library assertion */
    INJECT_SEGV,    /* a wild write */
    INJECT_OPEN,    /* opens /etc/passwd: refused by Landlock */
    INJECT_WRITE,   /* opens a file for writing: killed */
    INJECT_SOCKET,  /* socket(): killed */
    INJECT_EXEC,    /* execve(): killed */
    INJECT_FORK,    /* fork(): killed */
    INJECT_LOOP,    /* never ends: stopped at the time limit */
    INJECT_OOM,     /* allocates until malloc fails, then aborts */
    INJECT_REPLY,   /* sends a reply cut short, then waits */
    INJECT_SCRIBBLE /* keeps writing to its memfd after sending it */
};
static const char *const inject_names[] = {"",       "abort", "segv", "open", "write", "socket",
                                           "execve", "fork",  "loop", "oom",  "reply", "scribble"};
#define N_INJECT ((int)(sizeof inject_names / sizeof inject_names[0]))

typedef struct sbx_request {
    uint32_t magic, version;
    int32_t format, has_raw;
    vv_raw_params raw;
    int32_t series, channel, time, level;
    int32_t z_first, z_count;
    uint64_t budget;
    int32_t threads;
    int32_t inject;
    uint32_t cpu_seconds;
    int32_t op; /* SBX_OP_VOLUME, SBX_OP_DICOM_LIST, SBX_OP_MESH or SBX_OP_GRID */
    uint32_t path_len;
    char path[SBX_MAX_PATH];
} sbx_request;

/* A chunk asked of a long-lived reader (SBX_OP_BOXES): chunk c (chunk
 * indices along x, y, z) of a level. */
typedef struct sbx_box {
    uint32_t magic;
    int32_t level, c[3];
} sbx_box;

#define SBX_MAX_BOX_BYTES ((uint64_t)1 << 30)

/* 1 in volvis-reader: vv_volume_load reads in-process there. */
static int in_child;
/* The child's injected fault (INJECT_*), for the tests. */
static int inject;

int
vv_sandbox_wanted(const vv_volume_format *r) {
    if (in_child)
        return 0;
    if (r && !(r->flags & VV_FORMAT_FLAG_THIRD_PARTY))
        return 0;
    const char *e = getenv("VOLVIS_SANDBOX");
    return !(e && !strcmp(e, "0"));
}

int
vv_sandbox_in_reader(void) {
    return in_child;
}

/*
 * madvise(@p advice) over [@p p, @p p + @p len) in 8 MiB pieces on the
 * library's threads: the kernel populates or zaps the page tables of
 * different pieces in parallel (both take the mapping lock shared), where
 * one call does it on one core; a 150 MiB volume is 38 400 pages. @p p is
 * page-aligned. Used by both sides: the reader's memfd, the parent's
 * mapping of it. Advice the kernel refuses (MADV_POPULATE_* before Linux
 * 5.14) is ignored: the pages are then faulted in use.
 */
static void
madvise_parallel(void *p, size_t len, int advice) {
    const size_t piece = (size_t)8 << 20;
    const int64_t n = (int64_t)((len + piece - 1) / piece);
#pragma omp parallel for schedule(static) if (n > 1)
    for (int64_t i = 0; i < n; i++) {
        size_t off = (size_t)i * piece;
        (void)madvise((char *)p + off, len - off < piece ? len - off : piece, advice);
    }
}

/* ---- the child ------------------------------------------------------------ */

/* The voxels of the volumes the child makes: each in its own memfd. */
typedef struct sbx_block {
    void *data;
    size_t bytes;
    int fd;
} sbx_block;
static sbx_block blocks[8];
static pthread_mutex_t blocks_lock = PTHREAD_MUTEX_INITIALIZER;

static void *
memfd_alloc(size_t bytes) {
    size_t len = bytes ? bytes : 1;
    int fd = memfd_create("volvis-voxels", MFD_CLOEXEC | MFD_ALLOW_SEALING);
    if (fd < 0)
        return NULL;
    void *p = MAP_FAILED;
    if (ftruncate(fd, (off_t)len) == 0)
        p = mmap(NULL, len, PROT_READ | PROT_WRITE, MAP_SHARED, fd, 0);
    if (p == MAP_FAILED) {
        close(fd);
        return NULL;
    }
    /* the pages made ahead, in parallel (a fault a page costs more) */
    madvise_parallel(p, len, MADV_POPULATE_WRITE);
    pthread_mutex_lock(&blocks_lock);
    int slot = -1;
    for (int i = 0; i < (int)(sizeof blocks / sizeof blocks[0]) && slot < 0; i++)
        if (!blocks[i].data)
            slot = i;
    if (slot >= 0)
        blocks[slot] = (sbx_block){p, len, fd};
    pthread_mutex_unlock(&blocks_lock);
    if (slot < 0) {
        munmap(p, len);
        close(fd);
        return NULL;
    }
    return p;
}

static void
memfd_release(void *user, void *data) {
    (void)user;
    pthread_mutex_lock(&blocks_lock);
    for (int i = 0; i < (int)(sizeof blocks / sizeof blocks[0]); i++)
        if (blocks[i].data == data) {
            munmap(data, blocks[i].bytes);
            close(blocks[i].fd);
            blocks[i] = (sbx_block){0};
        }
    pthread_mutex_unlock(&blocks_lock);
}

/* The memfd holding @p data; a copy into a new one when a reader made the
 * voxels some other way. -1 on failure. */
static int
memfd_of(void *data, size_t bytes) {
    for (int i = 0; i < (int)(sizeof blocks / sizeof blocks[0]); i++)
        if (blocks[i].data == data && blocks[i].bytes >= bytes)
            return blocks[i].fd;
    void *p = memfd_alloc(bytes);
    if (!p)
        return -1;
    memcpy(p, data, bytes);
    return memfd_of(p, bytes);
}

/* Landlock: the structures and constants of ABI 6, defined here where the
 * system's header is older (Debian 12's describes ABI 2). */
struct sbx_landlock_ruleset_attr {
    uint64_t handled_access_fs;
    uint64_t handled_access_net;
    uint64_t scoped;
};
#ifndef LANDLOCK_ACCESS_NET_BIND_TCP
#define LANDLOCK_ACCESS_NET_BIND_TCP (1ULL << 0)
#define LANDLOCK_ACCESS_NET_CONNECT_TCP (1ULL << 1)
#endif
#ifndef LANDLOCK_SCOPE_ABSTRACT_UNIX_SOCKET
#define LANDLOCK_SCOPE_ABSTRACT_UNIX_SOCKET (1ULL << 0)
#define LANDLOCK_SCOPE_SIGNAL (1ULL << 1)
#endif

/* Read access beneath the folder of @p path (the folder itself when it is
 * one) and nothing else on any file system; no TCP; no signals to or
 * abstract sockets of processes outside. Returns 0, or -1 with errno (the
 * kernel has no Landlock: ENOSYS or EOPNOTSUPP). */
static int
landlock_restrict(const char *path) {
    long abi = syscall(SYS_landlock_create_ruleset, NULL, 0, LANDLOCK_CREATE_RULESET_VERSION);
    if (abi < 1)
        return -1;
    struct sbx_landlock_ruleset_attr ra = {0};
    ra.handled_access_fs = abi >= 5   ? 0xffffULL
                           : abi >= 3 ? 0x7fffULL
                           : abi >= 2 ? 0x3fffULL
                                      : 0x1fffULL;
    if (abi >= 4)
        ra.handled_access_net = LANDLOCK_ACCESS_NET_BIND_TCP | LANDLOCK_ACCESS_NET_CONNECT_TCP;
    if (abi >= 6)
        ra.scoped = LANDLOCK_SCOPE_ABSTRACT_UNIX_SOCKET | LANDLOCK_SCOPE_SIGNAL;
    size_t size = abi >= 6 ? sizeof ra : abi >= 4 ? 2 * sizeof(uint64_t) : sizeof(uint64_t);
    int rs = (int)syscall(SYS_landlock_create_ruleset, &ra, size, 0);
    if (rs < 0)
        return -1;
    /* the folder of the input, by the name given and by its real path; the
     * memory cgroup's files, which the memory budget's check reads */
    char dirs[3][SBX_MAX_PATH];
    int nd = 0;
    if (vv_memory_cgroup_root(dirs[0], sizeof dirs[0]))
        nd++;
    char *real = realpath(path, NULL);
    const char *names[2] = {path, real};
    for (int i = 0; i < 2; i++) {
        if (!names[i])
            continue;
        struct stat st;
        snprintf(dirs[nd], sizeof dirs[nd], "%s", names[i]);
        if (stat(names[i], &st) == 0 && !S_ISDIR(st.st_mode)) {
            char *slash = strrchr(dirs[nd], '/');
            if (!slash)
                snprintf(dirs[nd], sizeof dirs[nd], ".");
            else if (slash == dirs[nd])
                slash[1] = '\0';
            else
                *slash = '\0';
        }
        nd++;
    }
    free(real);
    int ok = 1;
    for (int i = 0; i < nd && ok; i++) {
        struct landlock_path_beneath_attr pb = {0};
        pb.allowed_access = LANDLOCK_ACCESS_FS_READ_FILE | LANDLOCK_ACCESS_FS_READ_DIR;
        pb.parent_fd = open(dirs[i], O_PATH | O_CLOEXEC);
        if (pb.parent_fd < 0)
            continue;
        if (syscall(SYS_landlock_add_rule, rs, LANDLOCK_RULE_PATH_BENEATH, &pb, 0) != 0)
            ok = 0;
        close(pb.parent_fd);
    }
    if (ok && syscall(SYS_landlock_restrict_self, rs, 0) != 0)
        ok = 0;
    int e = errno;
    close(rs);
    errno = e;
    return ok ? 0 : -1;
}

/* The system calls a reader needs to read files it may open, compute with
 * threads, and hand back its result; everything else ends the process
 * (SIGSYS). Returns 0 or -1. */
/* VOLVIS_SANDBOX_DEBUG: the forbidden call's number on stderr, then the
 * same end (SIGSYS). */
static void
on_sigsys(int sig, siginfo_t *si, void *uc) {
    (void)uc;
    char msg[96];
    int n = snprintf(msg, sizeof msg, "volvis-reader: forbidden system call %d\n", si->si_syscall);
    if (n > 0 && write(2, msg, (size_t)n) < 0)
        n = 0;
    signal(sig, SIG_DFL);
    raise(sig);
}

static int
seccomp_restrict(void) {
    uint32_t deny = SCMP_ACT_KILL_PROCESS;
    if (getenv("VOLVIS_SANDBOX_DEBUG")) {
        struct sigaction sa;
        memset(&sa, 0, sizeof sa);
        sa.sa_sigaction = on_sigsys;
        sa.sa_flags = SA_SIGINFO;
        sigaction(SIGSYS, &sa, NULL);
        deny = SCMP_ACT_TRAP;
    }
    scmp_filter_ctx c = seccomp_init(deny);
    if (!c)
        return -1;
    static const char *const allowed[] = {"read",
                                          "pread64",
                                          "readv",
                                          "preadv",
                                          "preadv2",
                                          "write",
                                          "writev",
                                          "pwrite64",
                                          "lseek",
                                          "close",
                                          "fstat",
                                          "newfstatat",
                                          "statx",
                                          "stat",
                                          "lstat",
                                          "fstatfs",
                                          "statfs",
                                          "getdents64",
                                          "fcntl",
                                          "dup",
                                          "dup2",
                                          "dup3",
                                          "readlink",
                                          "readlinkat",
                                          "access",
                                          "faccessat",
                                          "faccessat2",
                                          "getcwd",
                                          "fadvise64",
                                          "munmap",
                                          "mremap",
                                          "madvise",
                                          "brk",
                                          "futex",
                                          "futex_waitv",
                                          "set_robust_list",
                                          "get_robust_list",
                                          "rseq",
                                          "set_tid_address",
                                          "rt_sigaction",
                                          "rt_sigprocmask",
                                          "rt_sigreturn",
                                          "sigaltstack",
                                          "gettid",
                                          "getpid",
                                          "getppid",
                                          "exit",
                                          "exit_group",
                                          "restart_syscall",
                                          "clock_gettime",
                                          "clock_getres",
                                          "clock_nanosleep",
                                          "nanosleep",
                                          "gettimeofday",
                                          "time",
                                          "sched_yield",
                                          "sched_getaffinity",
                                          "sched_getparam",
                                          "sched_getscheduler",
                                          "getrandom",
                                          "memfd_create",
                                          "ftruncate",
                                          "sendmsg",
                                          "recvmsg",
                                          "recvfrom",
                                          "poll",
                                          "ppoll",
                                          "getuid",
                                          "geteuid",
                                          "getgid",
                                          "getegid",
                                          "uname",
                                          "sysinfo",
                                          "getrusage",
                                          "times",
                                          "getrlimit",
                                          "membarrier",
                                          "mincore",
                                          "msync"};
    int rc = 0;
    for (size_t i = 0; i < sizeof allowed / sizeof allowed[0] && rc == 0; i++) {
        int nr = seccomp_syscall_resolve_name(allowed[i]);
        if (nr != __NR_SCMP_ERROR)
            rc = seccomp_rule_add(c, SCMP_ACT_ALLOW, nr, 0);
    }
    /* files: read-only opens only */
    const scmp_datum_t wflags =
        O_WRONLY | O_RDWR | O_CREAT | O_TRUNC | O_APPEND | (O_TMPFILE & ~O_DIRECTORY);
    if (rc == 0)
        rc = seccomp_rule_add(c, SCMP_ACT_ALLOW, SCMP_SYS(openat), 1,
                              SCMP_A2(SCMP_CMP_MASKED_EQ, wflags, 0));
    if (rc == 0)
        rc = seccomp_rule_add(c, SCMP_ACT_ALLOW, SCMP_SYS(open), 1,
                              SCMP_A1(SCMP_CMP_MASKED_EQ, wflags, 0));
    /* memory: never executable */
    if (rc == 0)
        rc = seccomp_rule_add(c, SCMP_ACT_ALLOW, SCMP_SYS(mmap), 1,
                              SCMP_A2(SCMP_CMP_MASKED_EQ, PROT_EXEC, 0));
    if (rc == 0)
        rc = seccomp_rule_add(c, SCMP_ACT_ALLOW, SCMP_SYS(mprotect), 1,
                              SCMP_A2(SCMP_CMP_MASKED_EQ, PROT_EXEC, 0));
    /* threads, not processes; clone3 says ENOSYS so that glibc uses clone */
    if (rc == 0)
        rc = seccomp_rule_add(c, SCMP_ACT_ALLOW, SCMP_SYS(clone), 1,
                              SCMP_A0(SCMP_CMP_MASKED_EQ, CLONE_THREAD, CLONE_THREAD));
    if (rc == 0)
        rc = seccomp_rule_add(c, SCMP_ACT_ERRNO(ENOSYS), SCMP_SYS(clone3), 0);
    /* signals to its own threads only (abort, raise) */
    if (rc == 0)
        rc = seccomp_rule_add(c, SCMP_ACT_ALLOW, SCMP_SYS(tgkill), 1,
                              SCMP_A0(SCMP_CMP_EQ, (scmp_datum_t)getpid(), 0));
    /* getrlimit through prlimit64, never setting */
    if (rc == 0)
        rc =
            seccomp_rule_add(c, SCMP_ACT_ALLOW, SCMP_SYS(prlimit64), 1, SCMP_A2(SCMP_CMP_EQ, 0, 0));
    /* shared advisory locks and their release (libhdf5 locks a NetCDF-4
     * file it reads); an exclusive lock could hold up other programs */
    for (int i = 0; i < 3 && rc == 0; i++) {
        static const scmp_datum_t ops[3] = {LOCK_SH, LOCK_SH | LOCK_NB, LOCK_UN};
        rc = seccomp_rule_add(c, SCMP_ACT_ALLOW, SCMP_SYS(flock), 1,
                              SCMP_A1(SCMP_CMP_EQ, ops[i], 0));
    }
    /* isatty and other terminal queries: "not a terminal" */
    if (rc == 0)
        rc = seccomp_rule_add(c, SCMP_ACT_ERRNO(ENOTTY), SCMP_SYS(ioctl), 0);
    /* send() without an address (glibc's send is sendto) */
    if (rc == 0)
        rc = seccomp_rule_add(c, SCMP_ACT_ALLOW, SCMP_SYS(sendto), 1, SCMP_A4(SCMP_CMP_EQ, 0, 0));
    if (rc == 0)
        rc = seccomp_load(c);
    seccomp_release(c);
    return rc == 0 ? 0 : -1;
}

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
send_reply(const sbx_reply *r, int fd_to_pass) {
    struct iovec io = {(void *)r, offsetof(sbx_reply, err) + r->err_len};
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

/* The child's address-space limit: the voxels and a copy of them (the
 * memory budget twice), the libraries' own buffers and the executable's
 * mappings (1 GiB), a thread stack and a malloc arena per thread. */
static uint64_t
address_limit(uint64_t budget, int threads) {
    return 2 * budget + ((uint64_t)1 << 30) + (uint64_t)(threads > 0 ? threads : 1) * (72u << 20);
}

/* The limits of the child: no core file; CPU seconds; address space from
 * the memory budget (not under a sanitizer, whose shadow memory is
 * terabytes of address space). */
static void
set_limits(const sbx_request *rq) {
    struct rlimit no_core = {0, 0};
    setrlimit(RLIMIT_CORE, &no_core);
    struct rlimit cpu = {rq->cpu_seconds, (rlim_t)rq->cpu_seconds + 5};
    if (rq->cpu_seconds > 0) /* 0: a long-lived reader, timed request by request */
        setrlimit(RLIMIT_CPU, &cpu);
    /* the reader writes only its memfds, which a file-size limit of the
     * caller's (ulimit -f) would cut with SIGXFSZ: up to the hard limit,
     * and a write past that fails (EFBIG) instead of ending the reader */
    struct rlimit fsize;
    if (getrlimit(RLIMIT_FSIZE, &fsize) == 0 && fsize.rlim_cur != fsize.rlim_max) {
        fsize.rlim_cur = fsize.rlim_max;
        setrlimit(RLIMIT_FSIZE, &fsize);
    }
    signal(SIGXFSZ, SIG_IGN);
#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
#define VV_SBX_SANITIZER 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer) || __has_feature(thread_sanitizer) ||                         \
    __has_feature(memory_sanitizer)
#define VV_SBX_SANITIZER 1
#endif
#endif
#ifndef VV_SBX_SANITIZER
    uint64_t as = address_limit(rq->budget, rq->threads);
    struct rlimit r_as = {(rlim_t)as, (rlim_t)as};
    setrlimit(RLIMIT_AS, &r_as);
#endif
    prctl(PR_SET_DUMPABLE, 0, 0, 0, 0);
}

/* The child names the format it reads (so that a crash can be named after
 * its reader), then misbehaves when a test asked it to. */
static void
announce(const sbx_request *rq, vv_format f) {
    sbx_reply fr = {.magic = SBX_MAGIC, .kind = SBX_FORMAT, .format = (int32_t)f};
    send_reply(&fr, -1);
    if (rq->inject > INJECT_NONE && rq->inject < N_INJECT)
        misbehave(rq->inject);
}

/* @p fd sealed for handing over (the parent maps it), or -1 when it is -1
 * or cannot be sealed (then closed): this process's mapping of it is
 * removed first, so that it can be sealed against writing too (a memfd
 * with a writable shared mapping cannot be); nothing can change its bytes
 * once the parent has it. The injected "scribble" keeps its mapping and
 * hands it over unsealed against writing, as a hostile reader would. */
static int
sealed(int fd) {
    if (fd < 0)
        return -1;
    unsigned seals = F_SEAL_SHRINK | F_SEAL_GROW | F_SEAL_WRITE | F_SEAL_SEAL;
    if (inject == INJECT_SCRIBBLE) {
        seals = F_SEAL_SHRINK | F_SEAL_GROW;
    } else {
        pthread_mutex_lock(&blocks_lock);
        for (int i = 0; i < (int)(sizeof blocks / sizeof blocks[0]); i++)
            if (blocks[i].fd == fd && blocks[i].data) {
                /* the page tables dropped in parallel first (the memfd
                 * keeps the pages), so that the unmap has nothing to do */
                madvise_parallel(blocks[i].data, blocks[i].bytes, MADV_DONTNEED);
                munmap(blocks[i].data, blocks[i].bytes);
                blocks[i].data = NULL; /* the fd stays open: it is handed over */
            }
        pthread_mutex_unlock(&blocks_lock);
    }
    if (fcntl(fd, F_ADD_SEALS, seals) != 0) {
        close(fd);
        return -1;
    }
    return fd;
}

/* The child's last message: @p r with status @p s (and the error trace
 * when it failed) and @p fd, the memfd of the result; then it exits. */
static _Noreturn void
finish(sbx_reply *r, vv_status s, int fd) {
    r->status = s;
    if (s != VV_OK) {
        r->err_len = (uint32_t)snprintf(r->err, sizeof r->err, "%s", vv_error_message());
        if (r->err_len >= sizeof r->err)
            r->err_len = sizeof r->err - 1;
    }
    unsigned char *mine = MAP_FAILED;
    if (inject == INJECT_SCRIBBLE && s == VV_OK && r->bytes)
        mine = mmap(NULL, (size_t)r->bytes, PROT_READ | PROT_WRITE, MAP_SHARED, fd, 0);
    send_reply(r, s == VV_OK ? fd : -1);
    if (mine != MAP_FAILED)
        for (unsigned char v = 0;; v++) /* the parent must stop it first */
            memset(mine, v, (size_t)r->bytes);
    _exit(0);
}

/* One reply of the store server (status @p s, its error text when it
 * failed, @p fd handed over and closed). */
static void
box_reply(sbx_reply *r, vv_status s, int fd) {
    r->kind = SBX_RESULT;
    r->status = s;
    r->err_len = 0;
    if (s != VV_OK) {
        r->err_len = (uint32_t)snprintf(r->err, sizeof r->err, "%s", vv_error_message());
        if (r->err_len >= sizeof r->err)
            r->err_len = sizeof r->err - 1;
    }
    send_reply(r, s == VV_OK ? fd : -1);
    if (fd >= 0)
        close(fd);
}

/* The bytes of a store's window: its table, or its largest chunk. 0 when
 * a chunk is over SBX_MAX_BOX_BYTES. */
static uint64_t
window_bytes(const sbx_store_head *h) {
    uint64_t w = sizeof *h;
    for (int l = 0; l < h->n_levels; l++) {
        uint64_t c = vv_voxel_type_size((vv_voxel_type)h->lv[l].type);
        for (int k = 0; k < 3; k++)
            c *= (uint64_t)(h->lv[l].cdims[k] < h->lv[l].dims[k] ? h->lv[l].cdims[k]
                                                                 : h->lv[l].dims[k]);
        if (c > SBX_MAX_BOX_BYTES)
            return 0;
        w = c > w ? c : w;
    }
    return w;
}

/* The child's answer to SBX_OP_BOXES: the pyramid store's table (an
 * sbx_store_head at the start of the reader's window, a memfd sealed
 * against shrinking and growing, handed over once), then one chunk's
 * voxels in the window for each sbx_box until the parent closes its end. */
static _Noreturn void
serve_store(const sbx_request *rq, sbx_reply *r) {
    announce(rq, (vv_format)rq->format);
    pyr_store st;
    memset(&st, 0, sizeof st);
    vv_load_info info;
    memset(&info, 0, sizeof info);
    vv_status s = rq->inject == INJECT_OPEN
                      ? vv_error_set(VV_ERR_IO, "cannot open it")
                      : vv_pyr_store_open_local(&st, rq->path, rq->channel, rq->time, &info);
    int fd = -1;
    unsigned char *win = MAP_FAILED;
    static sbx_store_head head;
    uint64_t wbytes = 0;
    if (s == VV_OK) {
        head.n_levels = st.n_levels;
        head.n_channels = st.n_channels;
        head.n_times = st.n_times;
        head.has_range = st.has_range;
        memcpy(head.range, st.range, sizeof head.range);
        for (int l = 0; l < st.n_levels; l++) {
            const vv_volume *h = st.lv[l].hdr;
            memcpy(head.lv[l].dims, h->dims, sizeof head.lv[l].dims);
            memcpy(head.lv[l].cdims, st.lv[l].cdims, sizeof head.lv[l].cdims);
            head.lv[l].type = h->type;
            head.lv[l].unit = h->unit;
            memcpy(head.lv[l].spacing, h->spacing, sizeof head.lv[l].spacing);
            memcpy(head.lv[l].origin, h->origin, sizeof head.lv[l].origin);
        }
        r->has_color = info.has_color;
        memcpy(r->color, info.color, sizeof r->color);
        memcpy(r->channel_name, info.channel_name, sizeof r->channel_name);
        if (!(wbytes = window_bytes(&head)))
            s = vv_error_set(VV_ERR_LIMIT, "chunks of over %llu bytes",
                             (unsigned long long)SBX_MAX_BOX_BYTES);
    }
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
    box_reply(r, s, fd);
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
        r->format = rq->format;
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
        box_reply(r, s, -1);
    }
}

/* The child's answer to SBX_OP_DICOM_LIST: the vv_dicom_series array in
 * a sealed memfd (bytes = n * sizeof (vv_dicom_series), dims[0] = n). */
static _Noreturn void
list_series(const sbx_request *rq, sbx_reply *r) {
    r->format = VV_FORMAT_DICOM;
    announce(rq, VV_FORMAT_DICOM);
    vv_dicom_series *ser = NULL;
    int n = 0, fd = -1;
    vv_status s = rq->inject == INJECT_OPEN ? VV_ERR_IO : vv_dicom_list(&ser, &n, rq->path);
    if (s == VV_OK) {
        r->bytes = (uint64_t)n * sizeof *ser;
        r->dims[0] = n;
        if ((fd = sealed(memfd_of(ser, (size_t)r->bytes))) < 0) /* a copy in a new memfd */
            s = vv_error_set(VV_ERR_NOMEM, "the reader could not hand over %d series", n);
    }
    free(ser);
    finish(r, s, fd);
}

/* The child's answer to SBX_OP_MESH: the positions (3 float32 a vertex)
 * then the triangles (3 uint32 each) in a sealed memfd. */
static _Noreturn void
read_mesh(const sbx_request *rq, sbx_reply *r) {
    r->format = VV_FORMAT_UNKNOWN;
    announce(rq, VV_FORMAT_UNKNOWN);
    vv_mesh *m = NULL;
    int fd = -1;
    vv_status s = rq->inject == INJECT_OPEN ? VV_ERR_IO : vv_mesh_load(&m, rq->path);
    if (s == VV_OK) {
        size_t pos = m->n_vertices * 3 * sizeof(float), tri = m->n_triangles * 3 * sizeof(uint32_t);
        r->n_vertices = m->n_vertices;
        r->n_triangles = m->n_triangles;
        r->bytes = (uint64_t)(pos + tri);
        char *p = memfd_alloc(pos + tri);
        if (p) {
            memcpy(p, m->positions, pos);
            memcpy(p + pos, m->triangles, tri);
            fd = sealed(memfd_of(p, pos + tri));
        }
        if (fd < 0)
            s = vv_error_set(VV_ERR_NOMEM, "the reader could not hand over the mesh");
    }
    vv_mesh_free(m);
    finish(r, s, fd);
}

/* Bytes rounded up to a multiple of 8 (the grid memfd's sections). */
static uint64_t
pad8(uint64_t n) {
    return (n + 7) & ~(uint64_t)7;
}

/* The child's answer to SBX_OP_GRID: the grid in one sealed memfd, laid
 * out as sbx_grid_head says. */
static _Noreturn void
read_grid(const sbx_request *rq, sbx_reply *r) {
    r->format = VV_FORMAT_UNKNOWN;
    announce(rq, VV_FORMAT_UNKNOWN);
    vv_grid *g = NULL;
    int fd = -1;
    vv_status s = rq->inject == INJECT_OPEN ? VV_ERR_IO : vv_grid_load(&g, rq->path);
    if (s == VV_OK) {
        const int sph = g->kind == VV_GRID_SPHERICAL;
        const uint64_t n_conn = g->n_cells ? g->cell_offsets[g->n_cells] : 0;
        const uint64_t n_axes =
            sph ? (uint64_t)g->sph_dims[0] + (uint64_t)g->sph_dims[1] + (uint64_t)g->sph_dims[2]
                : 0;
        uint64_t bytes = pad8(sizeof(sbx_grid_head)) + pad8(g->n_points * 3 * sizeof(double)) +
                         pad8(g->n_cells) + pad8((g->n_cells + 1) * sizeof(uint64_t)) +
                         pad8(n_conn * sizeof(uint32_t)) +
                         pad8((uint64_t)g->n_blocks * 3 * sizeof(int32_t)) + n_axes * 8;
        for (int i = 0; i < g->n_fields; i++)
            bytes += sizeof(sbx_grid_field) +
                     pad8(g->fields[i].n_tuples * (uint64_t)g->fields[i].n_components * 4);
        char *p = memfd_alloc((size_t)bytes), *q = p;
        if (p) {
            sbx_grid_head h = {.kind = g->kind,
                               .n_fields = g->n_fields,
                               .n_blocks = g->n_blocks,
                               .n_points = g->n_points,
                               .n_cells = g->n_cells,
                               .n_conn = n_conn};
            if (sph)
                memcpy(h.sph_dims, g->sph_dims, sizeof h.sph_dims);
            memcpy(q, &h, sizeof h);
            q += pad8(sizeof h);
            memcpy(q, g->points, g->n_points * 3 * sizeof(double));
            q += pad8(g->n_points * 3 * sizeof(double));
            memcpy(q, g->cell_types, g->n_cells);
            q += pad8(g->n_cells);
            for (size_t c = 0; c <= g->n_cells; c++) {
                uint64_t o = g->n_cells ? g->cell_offsets[c] : 0;
                memcpy(q + 8 * c, &o, 8);
            }
            q += pad8((g->n_cells + 1) * sizeof(uint64_t));
            memcpy(q, g->connectivity, n_conn * sizeof(uint32_t));
            q += pad8(n_conn * sizeof(uint32_t));
            for (int b = 0; b < g->n_blocks; b++)
                for (int a = 0; a < 3; a++) {
                    int32_t d = g->block_dims[b][a];
                    memcpy(q + 4 * (3 * b + a), &d, 4);
                }
            q += pad8((uint64_t)g->n_blocks * 3 * sizeof(int32_t));
            for (int a = 0; a < 3 && sph; a++) {
                memcpy(q, g->sph_axes[a], (size_t)g->sph_dims[a] * sizeof(double));
                q += (size_t)g->sph_dims[a] * sizeof(double);
            }
            for (int i = 0; i < g->n_fields; i++) {
                const vv_grid_field *f = &g->fields[i];
                sbx_grid_field fh = {.cell_data = f->cell_data,
                                     .n_components = f->n_components,
                                     .has_fill = f->has_fill,
                                     .fill = f->fill,
                                     .n_tuples = f->n_tuples};
                memcpy(fh.name, f->name, sizeof fh.name);
                memcpy(q, &fh, sizeof fh);
                q += sizeof fh;
                memcpy(q, f->values, f->n_tuples * (size_t)f->n_components * sizeof(float));
                q += pad8(f->n_tuples * (uint64_t)f->n_components * 4);
            }
            r->bytes = bytes;
            fd = sealed(memfd_of(p, (size_t)bytes));
        }
        if (fd < 0)
            s = vv_error_set(VV_ERR_NOMEM, "the reader could not hand over the grid");
    }
    vv_grid_free(g);
    finish(r, s, fd);
}

int
vv_sandbox_reader_main(int argc, char **argv) {
    (void)argc;
    (void)argv;
    in_child = 1;
    if (fcntl(SBX_FD, F_GETFD) < 0) {
        fprintf(stderr, "volvis-reader: started by VolVis's loader only (it reads its request "
                        "from descriptor 3)\n");
        return 2;
    }
    static sbx_request rq;
    ssize_t n;
    while ((n = recv(SBX_FD, &rq, sizeof rq, 0)) < 0 && errno == EINTR)
        ;
    if (n == 0) /* a spare reader whose program ended: nothing to do */
        _exit(0);
    if (n != (ssize_t)sizeof rq || rq.magic != SBX_MAGIC || rq.version != SBX_VERSION ||
        rq.path_len == 0 || rq.path_len >= SBX_MAX_PATH) {
        fprintf(stderr, "volvis-reader: malformed request on descriptor 3\n");
        return 2;
    }
    rq.path[rq.path_len] = '\0';
    inject = rq.inject > INJECT_NONE && rq.inject < N_INJECT ? rq.inject : INJECT_NONE;
    static sbx_reply r;
    r.magic = SBX_MAGIC;
    r.kind = SBX_RESULT;
    r.format = rq.format;

    vv_memory_budget_set(rq.budget);
    vv_threads_set(rq.threads);
    set_limits(&rq);
    if (prctl(PR_SET_NO_NEW_PRIVS, 1, 0, 0, 0) != 0 ||
        (landlock_restrict(rq.path) != 0 && errno != ENOSYS && errno != EOPNOTSUPP) ||
        seccomp_restrict() != 0) {
        int e = errno;
        finish(&r,
               vv_error_set(VV_ERR_UNSUPPORTED, "the reader sandbox could not be set up (%s)",
                            strerror(e)),
               -1);
    }
    /* from here on, what the file makes the parser do stays in here */
    vv_volume_set_allocator(memfd_alloc, memfd_release);
    if (rq.op == SBX_OP_DICOM_LIST)
        list_series(&rq, &r);
    if (rq.op == SBX_OP_MESH)
        read_mesh(&rq, &r);
    if (rq.op == SBX_OP_GRID)
        read_grid(&rq, &r);
    if (rq.op == SBX_OP_BOXES)
        serve_store(&rq, &r);
    vv_format f = (vv_format)rq.format;
    if (f == VV_FORMAT_AUTO) {
        f = vv_format_detect(rq.path);
        if (f == VV_FORMAT_UNKNOWN && rq.has_raw)
            f = VV_FORMAT_RAW;
    }
    announce(&rq, f);
    vv_volume *v = NULL;
    vv_load_info info;
    memset(&info, 0, sizeof info);
    vv_status s = VV_OK;
    if (rq.inject == INJECT_OPEN) {
        s = VV_ERR_IO;
    } else {
        vv_load_options o;
        vv_load_options_init(&o);
        o.format = f == VV_FORMAT_UNKNOWN ? VV_FORMAT_AUTO : f;
        o.has_raw = rq.has_raw;
        o.raw = rq.raw;
        o.series = rq.series;
        o.channel = rq.channel;
        o.time = rq.time;
        o.level = rq.level;
        o.z_first = rq.z_first;
        o.z_count = rq.z_count;
        o.info = &info;
        s = vv_volume_load(&v, rq.path, &o);
    }
    r.format = (int32_t)f;
    int fd = -1;
    if (s == VV_OK) {
        memcpy(r.dims, v->dims, sizeof r.dims);
        r.type = v->type;
        memcpy(r.spacing, v->spacing, sizeof r.spacing);
        memcpy(r.origin, v->origin, sizeof r.origin);
        memcpy(r.direction, v->direction, sizeof r.direction);
        r.unit = v->unit;
        r.data_origin = v->data_origin;
        r.n_channels = info.n_channels;
        r.n_times = info.n_times;
        r.n_levels = info.n_levels;
        r.n_slices = info.n_slices;
        r.has_color = info.has_color;
        memcpy(r.color, info.color, sizeof r.color);
        r.time_step = info.time_step;
        r.has_raw_layout = info.has_raw_layout;
        r.raw_big_endian = info.raw_big_endian;
        r.raw_offset = info.raw_offset;
        r.raw_step_bytes = info.raw_step_bytes;
        r.raw_channel_bytes = info.raw_channel_bytes;
        memcpy(r.channel_name, info.channel_name, sizeof r.channel_name);
        r.modification = v->modification;
        r.space = v->space;
        r.bytes = vv_volume_voxel_count(v) * vv_voxel_type_size(v->type);
        if ((fd = sealed(memfd_of(v->data, (size_t)r.bytes))) < 0)
            s = vv_error_set(VV_ERR_NOMEM, "the reader could not hand over %llu bytes of voxels",
                             (unsigned long long)r.bytes);
    }
    finish(&r, s, fd);
}

/* ---- the parent ------------------------------------------------------------ */

/* The volvis-reader to start: $VOLVIS_READER, else the one beside this
 * program, the installed one, or the one of the build tree. */
static int
reader_path(char *buf, size_t cap) {
    const char *e = getenv("VOLVIS_READER");
    if (e && *e) {
        snprintf(buf, cap, "%s", e);
        return access(buf, X_OK) == 0;
    }
    char self[PATH_MAX];
    ssize_t n = readlink("/proc/self/exe", self, sizeof self - 1);
    if (n > 0) {
        self[n] = '\0';
        char *slash = strrchr(self, '/');
        if (slash) {
            *slash = '\0';
            if (snprintf(buf, cap, "%s/volvis-reader", self) < (int)cap && access(buf, X_OK) == 0)
                return 1;
        }
    }
#ifdef VV_READER_INSTALL_PATH
    snprintf(buf, cap, "%s", VV_READER_INSTALL_PATH);
    if (access(buf, X_OK) == 0)
        return 1;
#endif
#ifdef VV_READER_BUILD_PATH
    snprintf(buf, cap, "%s", VV_READER_BUILD_PATH);
    if (access(buf, X_OK) == 0)
        return 1;
#endif
    return 0;
}

static double
now_s(void) {
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

/* Seconds the child may run: 60 plus one per 10 MB of input (a folder's
 * files counted), or $VOLVIS_SANDBOX_TIMEOUT. */
static unsigned
time_limit(const char *path) {
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

static void
release_mapping(void *user, void *data) {
    munmap(data, (size_t)(uintptr_t)user);
}

/* The one line for a child that ended without a result. */
static vv_status
describe_end(int status, uint64_t peak, uint64_t budget, const char *fmt_name, const char *title,
             const char *file, unsigned limit, int timed_out) {
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
                (unsigned long long)(address_limit(budget, vv_threads_get()) >> 20));
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

static int
finite_all(const double *x, int n) {
    for (int i = 0; i < n; i++)
        if (!isfinite(x[i]))
            return 0;
    return 1;
}

/* The volume of a result reply and its memfd. Owns @p fd. */
static vv_status
volume_from_reply(vv_volume **out, vv_load_info *info, const sbx_reply *r, int fd,
                  const char *fmt_name, const char *file) {
    uint64_t bytes = 0;
    vv_status s = VV_OK;
    struct stat st;
    int seals = fd >= 0 ? fcntl(fd, F_GET_SEALS) : -1;
    if (fd < 0 || r->type < VV_U8 || r->type > VV_F64)
        s = vv_error_set(VV_ERR_FORMAT, "%s: %s: the reader's result has no voxels", fmt_name,
                         file);
    else if ((s = vv_volume_check_size(r->dims, (vv_voxel_type)r->type, &bytes)) != VV_OK)
        s = vv_error_prefix(s, "%s: %s: the reader's result", fmt_name, file);
    else if (bytes != r->bytes || fstat(fd, &st) != 0 || (uint64_t)st.st_size < bytes ||
             seals < 0 || !(seals & F_SEAL_SHRINK))
        s = vv_error_set(VV_ERR_FORMAT,
                         "%s: %s: the reader's result does not hold the %llu bytes it names",
                         fmt_name, file, (unsigned long long)bytes);
    else if (!(seals & F_SEAL_WRITE))
        s = vv_error_set(VV_ERR_FORMAT,
                         "%s: %s: the reader's voxels are not sealed against writing; the file is "
                         "hostile or the reader broken",
                         fmt_name, file);
    else if (!finite_all(r->spacing, 3) || !finite_all(r->origin, 3) ||
             !finite_all(r->direction, 9) || !(r->spacing[0] > 0) || !(r->spacing[1] > 0) ||
             !(r->spacing[2] > 0))
        s = vv_error_set(VV_ERR_FORMAT, "%s: %s: the reader's result has a broken geometry",
                         fmt_name, file);
    else if (r->n_channels < 0 || r->n_channels > VV_VOLUME_MAX_DIM || r->n_times < 0 ||
             r->n_times > VV_VOLUME_MAX_DIM || r->n_levels < 0 || r->n_levels > 64 ||
             r->n_slices < 0 || r->n_slices > VV_VOLUME_MAX_DIM ||
             !memchr(r->channel_name, 0, sizeof r->channel_name) ||
             !(r->time_step >= 0 && r->time_step < 1e12) ||
             !(r->color[0] >= 0 && r->color[0] <= 1 && r->color[1] >= 0 && r->color[1] <= 1 &&
               r->color[2] >= 0 && r->color[2] <= 1))
        s = vv_error_set(VV_ERR_FORMAT,
                         "%s: %s: the reader's result has broken channel or time axes", fmt_name,
                         file);
    if (s != VV_OK) {
        if (fd >= 0)
            close(fd);
        return s;
    }
    /* private: the memfd is sealed against writing; the page cache's pages
     * are mapped read-only (populated without copying) and copied only
     * where the program writes to the volume */
    size_t len = bytes ? (size_t)bytes : 1;
    void *p = mmap(NULL, len, PROT_READ | PROT_WRITE, MAP_PRIVATE, fd, 0);
    int e = errno;
    close(fd);
    if (p != MAP_FAILED)
        madvise_parallel(p, len, MADV_POPULATE_READ);
    if (p == MAP_FAILED)
        return vv_error_set(VV_ERR_NOMEM, "%s: %s: cannot map the reader's %llu bytes: %s",
                            fmt_name, file, (unsigned long long)bytes, strerror(e));
    vv_volume *v = NULL;
    s = vv_volume_wrap(&v, r->dims, (vv_voxel_type)r->type, p, release_mapping,
                       (void *)(uintptr_t)len);
    if (s != VV_OK) {
        munmap(p, len);
        return s;
    }
    memcpy(v->spacing, r->spacing, sizeof v->spacing);
    memcpy(v->origin, r->origin, sizeof v->origin);
    memcpy(v->direction, r->direction, sizeof v->direction);
    v->unit = r->unit >= 0 && r->unit <= VV_UNIT_UNKNOWN ? (vv_unit)r->unit : VV_UNIT_UNKNOWN;
    v->data_origin = r->data_origin >= 0 && r->data_origin <= VV_ORIGIN_OTHER
                         ? (vv_data_origin)r->data_origin
                         : VV_ORIGIN_OTHER;
    v->modification = r->modification >= 0 && r->modification <= VV_MOD_OTHER
                          ? (vv_modification)r->modification
                          : VV_MOD_OTHER;
    v->space = r->space == VV_SPACE_RAS || r->space == VV_SPACE_LPS ? (vv_space)r->space
                                                                    : VV_SPACE_UNKNOWN;
    memset(info, 0, sizeof *info);
    info->n_channels = r->n_channels;
    info->n_times = r->n_times;
    info->n_levels = r->n_levels;
    info->n_slices = r->n_slices;
    info->has_color = r->has_color != 0;
    memcpy(info->color, r->color, sizeof info->color);
    info->time_step = r->time_step;
    /* offsets into the file, checked against its size by their reader */
    info->has_raw_layout = r->has_raw_layout == 1 && r->raw_step_bytes == r->bytes;
    info->raw_big_endian = r->raw_big_endian != 0;
    info->raw_offset = r->raw_offset;
    info->raw_step_bytes = r->raw_step_bytes;
    info->raw_channel_bytes = r->raw_channel_bytes;
    memcpy(info->channel_name, r->channel_name, sizeof info->channel_name);
    *out = v;
    return VV_OK;
}

/* Starts volvis-reader with the parent's end of a new socket pair in
 * *@p sock. Returns 0 or an errno value. */
static int
spawn_reader(const char *exe, pid_t *pid, int *sock) {
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
    char **env = calloc(ne + 2, sizeof *env);
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
 * during each sandboxed load but a process's first, taken by the next one
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

static void
reap_later(pid_t pid) {
    pthread_mutex_lock(&spare_lock);
    reap_dying(0);
    if (n_dying == (int)(sizeof dying / sizeof dying[0]))
        reap_dying(1);
    dying[n_dying++] = pid;
    pthread_mutex_unlock(&spare_lock);
}

static int
take_reader(const char *exe, pid_t *pid, int *sock) {
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
    return spawn_reader(exe, pid, sock);
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
        if (spawn_reader(exe, &p, &fd) == 0) {
            spare_pid = p;
            spare_sock = fd;
            spare_owner = getpid();
            snprintf(spare_exe, sizeof spare_exe, "%s", exe);
        }
    }
    pthread_mutex_unlock(&spare_lock);
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

static const vv_volume_format *
record_of(vv_format f) {
    int n;
    const vv_volume_format *const *t = vv_volume_format_table(&n);
    return (int)f >= 1 && (int)f <= n ? t[(int)f - 1] : NULL;
}

/* The series list of a result reply and its memfd (copied: it is small).
 * Owns @p fd. */
static vv_status
series_from_reply(vv_dicom_series **out, int *n, const sbx_reply *r, int fd, const char *file) {
    struct stat st;
    int seals = fd >= 0 ? fcntl(fd, F_GET_SEALS) : -1;
    const int count = r->dims[0];
    vv_dicom_series *a = NULL;
    vv_status s = VV_OK;
    if (fd < 0 || count < 1 || count > SBX_MAX_SERIES || r->bytes != (uint64_t)count * sizeof *a ||
        fstat(fd, &st) != 0 || (uint64_t)st.st_size < r->bytes || seals < 0 ||
        !(seals & F_SEAL_SHRINK))
        s = vv_error_set(VV_ERR_FORMAT, "dicom: %s: the reader's list of series is malformed",
                         file);
    else if (!(a = malloc((size_t)r->bytes)))
        s = vv_error_set(VV_ERR_NOMEM, "out of memory");
    for (size_t got = 0; s == VV_OK && got < r->bytes;) {
        ssize_t k = pread(fd, (char *)a + got, (size_t)r->bytes - got, (off_t)got);
        if (k < 0 && errno == EINTR)
            continue;
        if (k <= 0)
            s = vv_error_set(VV_ERR_IO, "dicom: %s: cannot read the reader's list of series", file);
        else
            got += (size_t)k;
    }
    if (fd >= 0)
        close(fd);
    for (int i = 0; s == VV_OK && i < count; i++) {
        vv_dicom_series *e = &a[i];
        /* every string ends inside its field; no negative size */
        e->uid[sizeof e->uid - 1] = e->description[sizeof e->description - 1] = '\0';
        e->modality[sizeof e->modality - 1] = e->first_file[sizeof e->first_file - 1] = '\0';
        e->study_description[sizeof e->study_description - 1] = '\0';
        e->study_date[sizeof e->study_date - 1] = '\0';
        e->patient_name[sizeof e->patient_name - 1] = '\0';
        e->patient_id[sizeof e->patient_id - 1] = '\0';
        if (e->dims[0] < 0 || e->dims[1] < 0 || e->dims[2] < 0 || e->n_files < 0 ||
            e->time_steps < 1)
            s = vv_error_set(VV_ERR_FORMAT, "dicom: %s: the reader's list of series is malformed",
                             file);
    }
    if (s != VV_OK) {
        free(a);
        return s;
    }
    *out = a;
    *n = count;
    return VV_OK;
}

/* The mesh of a result reply and its memfd (copied into a new mesh, every
 * index checked; normals computed here). Owns @p fd. */
static vv_status
mesh_from_reply(vv_mesh **out, const sbx_reply *r, int fd, const char *file) {
    struct stat st;
    int seals = fd >= 0 ? fcntl(fd, F_GET_SEALS) : -1;
    const uint64_t nv = r->n_vertices, nt = r->n_triangles;
    vv_status s = VV_OK;
    if (fd < 0 || nv < 3 || nt < 1 || nv > VV_MESH_MAX_ELEMENTS || nt > VV_MESH_MAX_ELEMENTS ||
        r->bytes != nv * 3 * sizeof(float) + nt * 3 * sizeof(uint32_t) || fstat(fd, &st) != 0 ||
        (uint64_t)st.st_size < r->bytes || seals < 0 || !(seals & F_SEAL_SHRINK)) {
        if (fd >= 0)
            close(fd);
        return vv_error_set(VV_ERR_FORMAT, "mesh: %s: the reader's mesh is malformed", file);
    }
    void *p = mmap(NULL, (size_t)r->bytes, PROT_READ, MAP_SHARED, fd, 0);
    int e = errno;
    close(fd);
    if (p == MAP_FAILED)
        return vv_error_set(VV_ERR_NOMEM, "mesh: %s: cannot map the reader's %llu bytes: %s", file,
                            (unsigned long long)r->bytes, strerror(e));
    const float *pos = p;
    const uint32_t *tri = (const uint32_t *)((const char *)p + nv * 3 * sizeof(float));
    vv_mesh *m = NULL;
    if ((s = vv_mesh_new(&m)) == VV_OK &&
        (s = vv_mesh_reserve(m, (size_t)nv, (size_t)nt)) == VV_OK) {
        memcpy(m->positions, pos, (size_t)nv * 3 * sizeof(float));
        m->n_vertices = (size_t)nv;
        for (uint64_t i = 0; i < 3 * nv && s == VV_OK; i++)
            if (!isfinite(m->positions[i]))
                s = vv_error_set(VV_ERR_FORMAT, "vertex %llu is not finite",
                                 (unsigned long long)(i / 3));
        for (uint64_t t = 0; t < nt && s == VV_OK; t++) /* checks every index */
            s = vv_mesh_add_triangle(m, tri[3 * t], tri[3 * t + 1], tri[3 * t + 2]);
        if (s == VV_OK)
            s = vv_mesh_compute_normals(m);
    }
    munmap(p, (size_t)r->bytes);
    if (s != VV_OK) {
        vv_mesh_free(m);
        return vv_error_prefix(s, "mesh: %s: the reader's result", file);
    }
    *out = m;
    return VV_OK;
}

/* A cursor over a grid's memfd: take() hands out the next section of @p n
 * bytes (rounded up to 8), or NULL past the end. */
typedef struct grid_cursor {
    const char *p;
    uint64_t at, size;
} grid_cursor;

static const void *
take(grid_cursor *c, uint64_t n) {
    if (pad8(n) > c->size - c->at) /* n is bounded by the grid limits: no overflow */
        return NULL;
    const void *q = c->p + c->at;
    c->at += pad8(n);
    return q;
}

/* Copies the grid of a mapped memfd into @p g, checking what it copied. */
static vv_status
grid_copy(vv_grid *g, grid_cursor *c) {
    sbx_grid_head h;
    const void *q = take(c, sizeof h);
    if (!q)
        return vv_error_set(VV_ERR_FORMAT, "grid: no grid head");
    memcpy(&h, q, sizeof h);
    if (h.kind < VV_GRID_UNSTRUCTURED || h.kind > VV_GRID_SPHERICAL || h.n_fields < 0 ||
        h.n_fields > VV_GRID_MAX_FIELDS || h.n_blocks < 0 || h.n_blocks > VV_GRID_MAX_BLOCKS ||
        (h.kind == VV_GRID_CURVILINEAR) != (h.n_blocks > 0))
        return vv_error_set(VV_ERR_FORMAT, "grid: a grid head out of range");
    vv_status s = vv_grid_alloc(g, (size_t)h.n_points, (size_t)h.n_cells, (size_t)h.n_conn);
    if (s != VV_OK)
        return s;
    g->kind = (vv_grid_kind)h.kind;
    const uint64_t np = h.n_points, nc = h.n_cells, nk = h.n_conn;
    if (!(q = take(c, np * 3 * sizeof(double))))
        return vv_error_set(VV_ERR_FORMAT, "grid: %llu points past its end",
                            (unsigned long long)np);
    memcpy(g->points, q, (size_t)np * 3 * sizeof(double));
    for (uint64_t i = 0; i < 3 * np; i++)
        if (!isfinite(g->points[i]))
            return vv_error_set(VV_ERR_FORMAT, "grid: point %llu is not finite",
                                (unsigned long long)(i / 3));
    if (!(q = take(c, nc)))
        return vv_error_set(VV_ERR_FORMAT, "grid: %llu cells past its end", (unsigned long long)nc);
    memcpy(g->cell_types, q, (size_t)nc);
    if (!(q = take(c, (nc + 1) * sizeof(uint64_t))))
        return vv_error_set(VV_ERR_FORMAT, "grid: cell offsets past its end");
    for (uint64_t i = 0; i <= nc; i++) {
        uint64_t o;
        memcpy(&o, (const char *)q + 8 * i, 8);
        if (o > nk)
            return vv_error_set(VV_ERR_FORMAT,
                                "grid: cell offset %llu is past the %llu point indices",
                                (unsigned long long)i, (unsigned long long)nk);
        g->cell_offsets[i] = (size_t)o;
    }
    if (nc && g->cell_offsets[nc] != nk)
        return vv_error_set(VV_ERR_FORMAT, "grid: the cells use %zu of %llu point indices",
                            g->cell_offsets[nc], (unsigned long long)nk);
    if (!(q = take(c, nk * sizeof(uint32_t))))
        return vv_error_set(VV_ERR_FORMAT, "grid: point indices past its end");
    memcpy(g->connectivity, q, (size_t)nk * sizeof(uint32_t));
    if (h.n_blocks) {
        if (!(q = take(c, (uint64_t)h.n_blocks * 3 * sizeof(int32_t))) ||
            !(g->block_dims = malloc((size_t)h.n_blocks * sizeof *g->block_dims)))
            return vv_error_set(q ? VV_ERR_NOMEM : VV_ERR_FORMAT, "grid: no room for %d blocks",
                                h.n_blocks);
        memcpy(g->block_dims, q, (size_t)h.n_blocks * sizeof *g->block_dims);
        g->n_blocks = h.n_blocks;
        uint64_t sum = 0;
        for (int b = 0; b < h.n_blocks; b++) {
            uint64_t k = 1;
            for (int a = 0; a < 3; a++) {
                const int d = g->block_dims[b][a];
                if (d < 2 || d > (int)VV_GRID_MAX_POINTS)
                    return vv_error_set(VV_ERR_FORMAT, "grid: block %d has a dimension of %d", b,
                                        d);
                k *= (uint64_t)d;
            }
            if ((sum += k) > np)
                break;
        }
        if (sum != np)
            return vv_error_set(VV_ERR_FORMAT, "grid: its blocks do not hold its %llu points",
                                (unsigned long long)np);
    }
    if (h.kind == VV_GRID_SPHERICAL) {
        uint64_t k = 1;
        for (int a = 0; a < 3; a++) {
            const int d = h.sph_dims[a];
            if (d < 2 || (uint64_t)d > np || (k *= (uint64_t)d) > np) {
                k = UINT64_MAX; /* never np */
                break;
            }
        }
        if (k != np)
            return vv_error_set(
                VV_ERR_FORMAT, "grid: spherical axes of %d x %d x %d values for %llu points",
                h.sph_dims[0], h.sph_dims[1], h.sph_dims[2], (unsigned long long)np);
        for (int a = 0; a < 3; a++) {
            const size_t d = (size_t)h.sph_dims[a];
            if (!(q = take(c, d * sizeof(double))) ||
                !(g->sph_axes[a] = malloc(d * sizeof(double))))
                return vv_error_set(q ? VV_ERR_NOMEM : VV_ERR_FORMAT, "grid: no room for an axis");
            memcpy(g->sph_axes[a], q, d * sizeof(double));
            g->sph_dims[a] = (int)d;
            for (size_t i = 0; i < d; i++)
                if (!isfinite(g->sph_axes[a][i]) ||
                    (i && !(g->sph_axes[a][i] > g->sph_axes[a][i - 1])))
                    return vv_error_set(VV_ERR_FORMAT, "grid: a spherical axis not increasing");
        }
    }
    for (int i = 0; i < h.n_fields; i++) {
        sbx_grid_field fh;
        if (!(q = take(c, sizeof fh)))
            return vv_error_set(VV_ERR_FORMAT, "grid: field %d past its end", i);
        memcpy(&fh, q, sizeof fh);
        fh.name[sizeof fh.name - 1] = '\0';
        for (char *ch = fh.name; *ch; ch++) /* printable, for messages and lists */
            if ((unsigned char)*ch < 0x20 || *ch == 0x7f)
                *ch = '?';
        vv_grid_field *f = NULL;
        if ((s = vv_grid_add_field(g, fh.name, fh.cell_data != 0, fh.n_components, &f)) != VV_OK)
            return s;
        if (fh.n_tuples != f->n_tuples)
            return vv_error_set(VV_ERR_FORMAT, "grid: field '%s' has %llu tuples for %zu", f->name,
                                (unsigned long long)fh.n_tuples, f->n_tuples);
        const uint64_t vb = (uint64_t)f->n_tuples * (uint64_t)f->n_components * sizeof(float);
        if (!(q = take(c, vb)))
            return vv_error_set(VV_ERR_FORMAT, "grid: field '%s' past its end", f->name);
        memcpy(f->values, q, (size_t)vb);
        f->has_fill = fh.has_fill != 0;
        f->fill = fh.fill;
        vv_grid_field_update_range(f);
    }
    return vv_grid_validate(g);
}

/* The grid of a result reply and its memfd (copied into a new grid, then
 * checked). Owns @p fd. */
static vv_status
grid_from_reply(vv_grid **out, const sbx_reply *r, int fd, const char *fmt_name, const char *file) {
    struct stat st;
    int seals = fd >= 0 ? fcntl(fd, F_GET_SEALS) : -1;
    if (fd < 0 || r->bytes < sizeof(sbx_grid_head) || r->bytes > ((uint64_t)1 << 46) ||
        fstat(fd, &st) != 0 || (uint64_t)st.st_size < r->bytes || seals < 0 ||
        !(seals & F_SEAL_SHRINK)) {
        if (fd >= 0)
            close(fd);
        return vv_error_set(VV_ERR_FORMAT, "%s: %s: the reader's grid is malformed", fmt_name,
                            file);
    }
    void *p = mmap(NULL, (size_t)r->bytes, PROT_READ, MAP_SHARED, fd, 0);
    int e = errno;
    close(fd);
    if (p == MAP_FAILED)
        return vv_error_set(VV_ERR_NOMEM, "%s: %s: cannot map the reader's %llu bytes: %s",
                            fmt_name, file, (unsigned long long)r->bytes, strerror(e));
    grid_cursor c = {p, 0, r->bytes};
    vv_grid *g = NULL;
    vv_status s = vv_grid_new(&g, VV_GRID_UNSTRUCTURED);
    if (s == VV_OK)
        s = grid_copy(g, &c);
    munmap(p, (size_t)r->bytes);
    if (s != VV_OK) {
        vv_grid_free(g);
        return vv_error_prefix(s, "%s: %s: the reader's", fmt_name, file);
    }
    *out = g;
    return VV_OK;
}

int
vv_sandbox_take_message(int op, const void *msg, size_t len, int fd, vv_format *seen,
                        const char *file, vv_sandbox_answer *a) {
    memset(a, 0, sizeof *a);
    vv_status *status = &a->status;
    sbx_reply *r = malloc(sizeof *r);
    if (!r) {
        if (fd >= 0)
            close(fd);
        *status = vv_error_set(VV_ERR_NOMEM, "out of memory");
        return 1;
    }
    int whole = len >= offsetof(sbx_reply, err) && len <= sizeof *r;
    if (whole) {
        memcpy(r, msg, len);
        whole = r->magic == SBX_MAGIC && r->err_len < SBX_MAX_ERROR &&
                len == offsetof(sbx_reply, err) + r->err_len &&
                (r->kind == SBX_FORMAT || r->kind == SBX_RESULT);
    }
    if (!whole || r->kind == SBX_FORMAT) {
        if (fd >= 0)
            close(fd);
        if (whole && record_of((vv_format)r->format))
            *seen = (vv_format)r->format;
        free(r);
        return whole ? 0 : -1;
    }
    r->err[r->err_len] = '\0';
    for (char *c = r->err; *c; c++) /* one line of printable text */
        if ((unsigned char)*c < 0x20 || *c == 0x7f)
            *c = ' ';
    const vv_volume_format *rec = record_of(*seen);
    const char *fmt_name = op == SBX_OP_GRID ? "grid" : rec ? rec->name : "load";
    if (r->status != VV_OK) {
        if (fd >= 0)
            close(fd);
        vv_status e =
            r->status >= VV_ERR_CANCELLED && r->status < 0 ? (vv_status)r->status : VV_ERR_FORMAT;
        *status = r->err[0] ? vv_error_set(e, "%s", r->err)
                            : vv_error_set(e, "%s: %s: the reader failed without a message",
                                           fmt_name, file);
    } else if (op == SBX_OP_DICOM_LIST) {
        *status = series_from_reply(&a->series, &a->n_series, r, fd, file);
    } else if (op == SBX_OP_MESH) {
        *status = mesh_from_reply(&a->mesh, r, fd, file);
    } else if (op == SBX_OP_GRID) {
        *status = grid_from_reply(&a->grid, r, fd, fmt_name, file);
    } else {
        *status = volume_from_reply(&a->volume, &a->info, r, fd, fmt_name, file);
    }
    free(r);
    return 1;
}

/* One message of a reader on @p sock into @p r: its length; 0 when the
 * reader is gone, -1 when interrupted (try again), -2 when the message or
 * its control data was cut (malformed). *passed: the descriptor it carried
 * (-1: none; of several, the last, the others closed; closed when cut). */
static ssize_t
recv_reply(int sock, sbx_reply *r, int *passed) {
    union {
        struct cmsghdr h;
        char buf[CMSG_SPACE(sizeof(int))];
    } u;
    struct iovec io = {r, sizeof *r};
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

/* The volvis-reader to run on @p path into @p exe (PATH_MAX bytes); errors
 * named "@p name: FILE": a path too long for a request, no reader found. */
static vv_status
reader_for(const char *name, const char *path, char *exe) {
    const char *file = vv_path_basename(path);
    if (strlen(path) >= SBX_MAX_PATH)
        return vv_error_set(VV_ERR_LIMIT, "%s: %s: a path of over %d bytes", name, file,
                            SBX_MAX_PATH - 1);
    if (!reader_path(exe, PATH_MAX))
        return vv_error_set(VV_ERR_IO,
                            "%s: %s: the sandboxed reader volvis-reader was not found (%s; set "
                            "VOLVIS_READER to its path, or VOLVIS_SANDBOX=0 to read in this "
                            "process)",
                            name, file, exe);
    return VV_OK;
}

/* A reader's request for @p op on @p path (malloc'd; NULL: out of
 * memory); @p path is shorter than SBX_MAX_PATH. */
static sbx_request *
new_request(int op, const char *path, vv_format f, const vv_load_options *opt) {
    static sbx_request proto; /* zeroes for the request's padding */
    sbx_request *rq = malloc(sizeof *rq);
    if (!rq)
        return NULL;
    *rq = proto;
    rq->magic = SBX_MAGIC;
    rq->version = SBX_VERSION;
    rq->format = (int32_t)f;
    rq->op = op;
    rq->has_raw = opt->has_raw;
    rq->raw = opt->raw;
    rq->series = opt->series;
    rq->channel = opt->channel;
    rq->time = opt->time;
    rq->level = opt->level;
    rq->z_first = opt->z_first;
    rq->z_count = opt->z_count;
    rq->budget = vv_memory_budget_get();
    rq->threads = vv_threads_get();
    rq->cpu_seconds = time_limit(path);
    rq->path_len = (uint32_t)strlen(path);
    memcpy(rq->path, path, rq->path_len);
    const char *inj = getenv("VOLVIS_SANDBOX_INJECT");
    for (int i = 1; inj && i < N_INJECT; i++)
        if (!strcmp(inj, inject_names[i]))
            rq->inject = i;
    return rq;
}

/* A reader's run for @p op on @p path (@p opt NULL: the defaults): its
 * result in *@p ans (zeroed first); returns ans->status, or the error of a
 * reader that ended without a result, naming the reader @p name and
 * @p title ("mesh", ".vtu"; NULL: the volume format the reader announced). */
static vv_status
run_reader(int op, const char *path, vv_format f, const vv_load_options *opt, const char *name,
           const char *title, vv_sandbox_answer *ans) {
    memset(ans, 0, sizeof *ans);
    vv_load_options defaults;
    if (!opt) {
        vv_load_options_init(&defaults);
        opt = &defaults;
    }
    const char *file = vv_path_basename(path);
    char exe[PATH_MAX];
    vv_status s0 = reader_for("load", path, exe);
    if (s0 != VV_OK)
        return s0;
    sbx_request *rq = new_request(op, path, f, opt);
    if (!rq)
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    uint64_t rq_budget = rq->budget;
    unsigned limit = rq->cpu_seconds;

    pid_t pid = -1;
    int sock = -1;
    int err = take_reader(exe, &pid, &sock);
    if (err != 0) {
        free(rq);
        return vv_error_set(VV_ERR_IO, "load: %s: cannot start %s: %s", file, exe, strerror(err));
    }
    ssize_t n;
    while ((n = send(sock, rq, sizeof *rq, MSG_NOSIGNAL)) < 0 && errno == EINTR)
        ;
    free(rq);
    /* a process's second load and later ones start the next reader while
     * this one reads (most programs that load once never load again: the
     * CLI's spare would only take a core from this load) */
    if (atomic_fetch_add(&loads_started, 1) > 0)
        refill_spare(exe);

    vv_format seen = f;
    sbx_reply *r = malloc(sizeof *r);
    int result = 0, timed_out = 0, malformed = 0, status = 0;
    vv_status s = VV_OK;
    double deadline = now_s() + limit + 5;
    while (r && !result && !malformed && n >= 0) {
        double left = deadline - now_s();
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
        const ssize_t got = recv_reply(sock, r, &passed);
        if (got == -1)
            continue;
        if (got == 0)
            break; /* the child is gone */
        if (got < 0) {
            malformed = 1;
            break;
        }
        int k = vv_sandbox_take_message(op, r, (size_t)got, passed, &seen, file, ans);
        if (k > 0)
            s = ans->status;
        result = k > 0;
        malformed = k < 0 || (k == 0 && passed >= 0); /* a memfd before the result */
    }
    close(sock);
    /* with its result sent the child has nothing left to do (reaped
     * later); without one it is stopped and its end described */
    uint64_t peak = 0;
    kill(pid, SIGKILL);
    if (result) {
        reap_later(pid);
    } else {
        struct rusage ru;
        memset(&ru, 0, sizeof ru);
        while (wait4(pid, &status, 0, &ru) < 0 && errno == EINTR)
            ;
        peak = (uint64_t)ru.ru_maxrss * 1024u;
    }
    const vv_volume_format *rec = record_of(seen);
    const char *fmt_name = name ? name : rec ? rec->name : "load";
    if (!title)
        title = rec ? rec->title : "file";
    if (!r) {
        s = vv_error_set(VV_ERR_NOMEM, "out of memory");
    } else if (malformed) {
        s = vv_error_set(VV_ERR_FORMAT,
                         "%s: %s: the %s reader sent a malformed reply and was stopped; the "
                         "file is hostile or the reader broken",
                         fmt_name, file, title);
    } else if (!result) {
        s = describe_end(status, peak, rq_budget, fmt_name, title, file, limit, timed_out);
    }
    free(r);
    return s;
}

vv_status
vv_sandbox_volume_load(vv_volume **out, const char *path, vv_format f, const vv_load_options *opt) {
    vv_sandbox_answer a;
    vv_status s = run_reader(SBX_OP_VOLUME, path, f, opt, NULL, NULL, &a);
    *out = a.volume;
    if (s == VV_OK && opt->info)
        *opt->info = a.info;
    return s;
}

vv_status
vv_sandbox_dicom_list(vv_dicom_series **out, int *n, const char *path) {
    vv_sandbox_answer a;
    vv_status s = run_reader(SBX_OP_DICOM_LIST, path, VV_FORMAT_DICOM, NULL, NULL, NULL, &a);
    *out = a.series;
    *n = a.n_series;
    return s;
}

vv_status
vv_sandbox_mesh_load(vv_mesh **out, const char *path) {
    vv_sandbox_answer a;
    vv_status s = run_reader(SBX_OP_MESH, path, VV_FORMAT_UNKNOWN, NULL, "mesh", "mesh", &a);
    *out = a.mesh;
    return s;
}

vv_status
vv_sandbox_grid_load(vv_grid **out, const char *path, const vv_grid_format_record *rec) {
    vv_sandbox_answer a;
    vv_status s = run_reader(SBX_OP_GRID, path, VV_FORMAT_UNKNOWN, NULL, rec->name, rec->title, &a);
    *out = a.grid;
    return s;
}

/* ---- the long-lived readers of a pyramid's store ------------------------------- */

#define SBX_MAX_READERS 16

enum { RD_IDLE, RD_BUSY, RD_AHEAD }; /* a reader: free, in a read, asked ahead */

typedef struct sbx_reader {
    pid_t pid;
    int sock, busy;           /* RD_* */
    int level, c[3];          /* RD_AHEAD: the chunk asked */
    const unsigned char *win; /* its window, mapped read-only (shared with it) */
    uint64_t wbytes;
} sbx_reader;

/* A pool of readers serving one store: each thread of the pyramid's
 * decode takes an idle one for a chunk. */
typedef struct sbx_store {
    const char *name, *title; /* the format's, for messages */
    char file[256];
    unsigned limit; /* seconds a request may take */
    uint64_t budget;
    int n;
    sbx_reader rd[SBX_MAX_READERS];
    pthread_mutex_t lock;
    pthread_cond_t idle;
    vv_status dead; /* VV_OK while the readers serve */
    char why[1024]; /* the first end, for every later read */
    sbx_store_head head;
} sbx_store;

/* Reader @p i's end: stopped, reaped and described; the store is dead
 * from then on (the first end's line repeated by every later read). */
static vv_status
store_fail(sbx_store *b, int i, int timed_out, int malformed) {
    int status = 0;
    struct rusage ru;
    memset(&ru, 0, sizeof ru);
    sbx_reader *rd = &b->rd[i];
    if (rd->pid > 0) {
        kill(rd->pid, SIGKILL);
        while (wait4(rd->pid, &status, 0, &ru) < 0 && errno == EINTR)
            ;
        rd->pid = -1;
    }
    if (rd->sock >= 0)
        close(rd->sock);
    rd->sock = -1;
    vv_status s = malformed ? vv_error_set(VV_ERR_FORMAT,
                                           "%s: %s: the %s reader sent a malformed reply and was "
                                           "stopped; the file is hostile or the reader broken",
                                           b->name, b->file, b->title)
                            : describe_end(status, (uint64_t)ru.ru_maxrss * 1024u, b->budget,
                                           b->name, b->title, b->file, b->limit, timed_out);
    pthread_mutex_lock(&b->lock);
    if (b->dead == VV_OK) {
        b->dead = s;
        snprintf(b->why, sizeof b->why, "%s", vv_error_message());
    }
    s = vv_error_set(b->dead, "%s", b->why);
    pthread_mutex_unlock(&b->lock);
    return s;
}

/* Reader @p i's next result into @p r, its memfd (or -1) into *fd; the
 * reader's own error when it sent one. */
static vv_status
store_wait(sbx_store *b, int i, sbx_reply *r, int *fd) {
    *fd = -1;
    const double deadline = now_s() + b->limit + 5;
    for (;;) {
        const double left = deadline - now_s();
        if (left <= 0)
            return store_fail(b, i, 1, 0);
        struct pollfd pf = {b->rd[i].sock, POLLIN, 0};
        if (poll(&pf, 1, (int)(left * 1000) + 1) <= 0)
            continue;
        int passed = -1;
        const ssize_t got = recv_reply(b->rd[i].sock, r, &passed);
        if (got == -1)
            continue;
        if (got == 0)
            return store_fail(b, i, 0, 0); /* the reader is gone */
        if (got < 0)
            return store_fail(b, i, 0, 1);
        const int whole = (size_t)got >= offsetof(sbx_reply, err) && r->magic == SBX_MAGIC &&
                          r->err_len < SBX_MAX_ERROR &&
                          (size_t)got == offsetof(sbx_reply, err) + r->err_len &&
                          (r->kind == SBX_FORMAT || r->kind == SBX_RESULT);
        if (!whole || (r->kind == SBX_FORMAT && passed >= 0)) {
            if (passed >= 0)
                close(passed);
            return store_fail(b, i, 0, 1);
        }
        if (r->kind == SBX_FORMAT)
            continue;
        r->err[r->err_len] = '\0';
        for (char *c = r->err; *c; c++) /* one line of printable text */
            if ((unsigned char)*c < 0x20 || *c == 0x7f)
                *c = ' ';
        if (r->status != VV_OK) {
            if (passed >= 0)
                close(passed);
            const vv_status e = r->status >= VV_ERR_CANCELLED && r->status < 0
                                    ? (vv_status)r->status
                                    : VV_ERR_FORMAT;
            return r->err[0] ? vv_error_set(e, "%s", r->err)
                             : vv_error_set(e, "the reader failed without a message");
        }
        *fd = passed;
        return VV_OK;
    }
}

/* Reader @p i's window, handed over as memfd @p fd of @p bytes (closed):
 * sealed against shrinking and growing (so that the mapping stays whole),
 * mapped read-only. The reader writes it: what is copied out of it is
 * only ever copied, never trusted. */
static vv_status
store_map(sbx_store *b, int i, int fd, uint64_t bytes) {
    struct stat st;
    const int seals = fd >= 0 ? fcntl(fd, F_GET_SEALS) : -1;
    if (fd < 0 || fstat(fd, &st) != 0 || (uint64_t)st.st_size != bytes || seals < 0 ||
        !(seals & F_SEAL_SHRINK) || !(seals & F_SEAL_GROW) || bytes < sizeof(sbx_store_head) ||
        bytes > SBX_MAX_BOX_BYTES) {
        if (fd >= 0)
            close(fd);
        return store_fail(b, i, 0, 1);
    }
    void *p = mmap(NULL, (size_t)bytes, PROT_READ, MAP_SHARED, fd, 0);
    const int e = errno;
    close(fd);
    if (p == MAP_FAILED)
        return vv_error_set(VV_ERR_NOMEM, "cannot map the reader's window of %llu bytes: %s",
                            (unsigned long long)bytes, strerror(e));
    b->rd[i].win = p;
    b->rd[i].wbytes = bytes;
    return VV_OK;
}

/* The table a reader sent, checked: levels, counts, geometry, range. */
static int
head_ok(const sbx_store_head *h) {
    if (h->n_levels < 1 || h->n_levels > VV_PYRAMID_MAX_LEVELS || h->n_channels < 1 ||
        h->n_channels > VV_VOLUME_MAX_DIM || h->n_times < 1 || h->n_times > VV_VOLUME_MAX_DIM ||
        (h->has_range &&
         !(isfinite(h->range[0]) && isfinite(h->range[1]) && h->range[1] >= h->range[0])))
        return 0;
    for (int l = 0; l < h->n_levels; l++) {
        const sbx_level *L = &h->lv[l];
        if (L->type < VV_U8 || L->type > VV_F64 || L->type != h->lv[0].type || L->unit < 0 ||
            L->unit > VV_UNIT_UNKNOWN)
            return 0;
        for (int k = 0; k < 3; k++)
            if (L->dims[k] < 1 || L->dims[k] > VV_VOLUME_MAX_DIM || L->cdims[k] < 1 ||
                L->cdims[k] > 4096 || !(L->spacing[k] > 0) || !isfinite(L->spacing[k]) ||
                !isfinite(L->origin[k]))
                return 0;
    }
    return 1;
}

/* Sends chunk @p c of @p level to reader @p i (reserved by the caller). */
static vv_status
store_ask(sbx_store *b, int i, int level, const int c[3]) {
    const sbx_box q = {SBX_MAGIC, level, {c[0], c[1], c[2]}};
    ssize_t sent;
    while ((sent = send(b->rd[i].sock, &q, sizeof q, MSG_NOSIGNAL)) < 0 && errno == EINTR)
        ;
    return sent == (ssize_t)sizeof q ? VV_OK : store_fail(b, i, 0, 0);
}

static vv_status
store_read_chunk(void *ctx, int level, const int c[3], unsigned char *scratch, unsigned char *dst,
                 const int org[3], const int dims[3], int *missing, uint64_t *file_bytes) {
    (void)scratch;
    (void)org;
    sbx_store *b = ctx;
    uint64_t bytes = vv_voxel_type_size((vv_voxel_type)b->head.lv[level].type);
    for (int k = 0; k < 3; k++)
        bytes *= (uint64_t)dims[k];
    /* the reader that was asked for this chunk ahead, else an idle one, else
     * one asked for another chunk ahead (its result dropped) */
    pthread_mutex_lock(&b->lock);
    int i = -1, asked = 0, stale = 0;
    while (b->dead == VV_OK && i < 0) {
        for (int k = 0; k < b->n && i < 0; k++)
            if (b->rd[k].busy == RD_AHEAD && b->rd[k].level == level && b->rd[k].c[0] == c[0] &&
                b->rd[k].c[1] == c[1] && b->rd[k].c[2] == c[2])
                i = k, asked = 1;
        for (int k = 0; k < b->n && i < 0; k++)
            if (b->rd[k].busy == RD_IDLE)
                i = k;
        for (int k = 0; k < b->n && i < 0; k++)
            if (b->rd[k].busy == RD_AHEAD)
                i = k, stale = 1;
        if (i < 0)
            pthread_cond_wait(&b->idle, &b->lock);
    }
    if (i < 0) {
        vv_status s = vv_error_set(b->dead, "%s", b->why);
        pthread_mutex_unlock(&b->lock);
        return s;
    }
    b->rd[i].busy = RD_BUSY;
    pthread_mutex_unlock(&b->lock);
    vv_status s = VV_OK;
    sbx_reply *r = malloc(sizeof *r);
    int fd = -1;
    if (!r)
        s = vv_error_set(VV_ERR_NOMEM, "out of memory");
    if (s == VV_OK && stale) { /* the other chunk's result, or its error, dropped */
        s = store_wait(b, i, r, &fd);
        if (fd >= 0)
            close(fd);
        fd = -1;
        s = b->dead == VV_OK ? VV_OK : vv_error_set(b->dead, "%s", b->why);
    }
    if (s == VV_OK && !asked)
        s = store_ask(b, i, level, c);
    if (s == VV_OK && (s = store_wait(b, i, r, &fd)) == VV_OK &&
        (r->bytes != bytes || bytes > b->rd[i].wbytes || fd >= 0)) {
        if (fd >= 0)
            close(fd);
        s = store_fail(b, i, 0, 1);
    } else if (s == VV_OK) {
        memcpy(dst, b->rd[i].win, (size_t)bytes); /* copied once, then only the copy is read */
        *missing = r->missing != 0;
        *file_bytes = r->file_bytes; /* statistics only */
    }
    free(r);
    pthread_mutex_lock(&b->lock);
    b->rd[i].busy = RD_IDLE;
    pthread_cond_broadcast(&b->idle);
    pthread_mutex_unlock(&b->lock);
    return s;
}

/* Asks an idle reader for chunk @p c of @p level ahead (pyr_store.prefetch). */
static int
store_prefetch(void *ctx, int level, const int c[3]) {
    sbx_store *b = ctx;
    pthread_mutex_lock(&b->lock);
    int i = -1, have = 0;
    for (int k = 0; k < b->n && b->dead == VV_OK; k++) {
        if (b->rd[k].busy == RD_AHEAD && b->rd[k].level == level && b->rd[k].c[0] == c[0] &&
            b->rd[k].c[1] == c[1] && b->rd[k].c[2] == c[2])
            have = 1;
        if (b->rd[k].busy == RD_IDLE && i < 0)
            i = k;
    }
    if (have || i < 0) {
        pthread_mutex_unlock(&b->lock);
        return have;
    }
    b->rd[i].busy = RD_AHEAD;
    b->rd[i].level = level;
    memcpy(b->rd[i].c, c, sizeof b->rd[i].c);
    pthread_mutex_unlock(&b->lock);
    return store_ask(b, i, level, c) == VV_OK;
}

static void
store_close(void *ctx) {
    sbx_store *b = ctx;
    if (!b)
        return;
    for (int i = 0; i < b->n; i++) {
        if (b->rd[i].win)
            munmap((void *)b->rd[i].win, (size_t)b->rd[i].wbytes);
        if (b->rd[i].sock >= 0)
            close(b->rd[i].sock); /* the reader's recv ends: it exits */
        if (b->rd[i].pid > 0) {
            kill(b->rd[i].pid, SIGKILL);
            reap_later(b->rd[i].pid);
        }
    }
    pthread_mutex_destroy(&b->lock);
    pthread_cond_destroy(&b->idle);
    free(b);
}

/* Starts the readers and takes the first's table; the others' must be
 * the same. */
static vv_status
store_start(sbx_store *b, const char *exe, const sbx_request *rq, vv_load_info *info) {
    for (int i = 0; i < b->n; i++) {
        int err = i == 0 ? take_reader(exe, &b->rd[i].pid, &b->rd[i].sock)
                         : spawn_reader(exe, &b->rd[i].pid, &b->rd[i].sock);
        if (err != 0)
            return vv_error_set(VV_ERR_IO, "cannot start %s: %s", exe, strerror(err));
        ssize_t sent;
        while ((sent = send(b->rd[i].sock, rq, sizeof *rq, MSG_NOSIGNAL)) < 0 && errno == EINTR)
            ;
    }
    sbx_reply *r = malloc(sizeof *r);
    sbx_store_head *h = malloc(sizeof *h);
    vv_status s = r && h ? VV_OK : vv_error_set(VV_ERR_NOMEM, "out of memory");
    for (int i = 0; i < b->n && s == VV_OK; i++) {
        int fd = -1;
        if ((s = store_wait(b, i, r, &fd)) != VV_OK)
            break;
        if ((s = store_map(b, i, fd, r->bytes)) == VV_OK) {
            memcpy(h, b->rd[i].win, sizeof *h);
            if (i == 0 && head_ok(h) && window_bytes(h) && window_bytes(h) <= r->bytes) {
                b->head = *h;
                if (info && memchr(r->channel_name, 0, sizeof r->channel_name)) {
                    info->has_color = r->has_color != 0;
                    for (int k = 0; k < 3; k++)
                        info->color[k] = r->color[k] >= 0 && r->color[k] <= 1 ? r->color[k] : 1;
                    memcpy(info->channel_name, r->channel_name, sizeof info->channel_name);
                }
            } else if (i == 0 || memcmp(h, &b->head, sizeof *h)) {
                s = store_fail(b, i, 0, 1);
            }
        }
    }
    free(r);
    free(h);
    return s;
}

vv_status
vv_sandbox_store_open(pyr_store *st, const char *path, int channel, int time, vv_load_info *info) {
    memset(st, 0, sizeof *st);
    const int h5 = vv_h5_is_hdf5(path);
    st->name = h5 ? "hdf5" : "zarr";
    char exe[PATH_MAX];
    vv_status s = reader_for(st->name, path, exe);
    if (s != VV_OK)
        return s;
    int nf;
    const vv_volume_format *const *t = vv_volume_format_table(&nf);
    vv_format f = VV_FORMAT_UNKNOWN;
    const char *title = h5 ? "HDF5" : "Zarr";
    for (int i = 0; i < nf; i++)
        if (!strcmp(t[i]->name, st->name)) {
            f = (vv_format)(i + 1);
            title = t[i]->title;
        }
    vv_load_options o;
    vv_load_options_init(&o);
    o.channel = channel;
    o.time = time;
    sbx_request *rq = new_request(SBX_OP_BOXES, path, f, &o);
    sbx_store *b = calloc(1, sizeof *b);
    if (!rq || !b) {
        free(rq);
        free(b);
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    }
    b->name = st->name;
    b->title = title;
    snprintf(b->file, sizeof b->file, "%s", vv_path_basename(path));
    b->limit = rq->cpu_seconds; /* a request's wall time; the reader's CPU is not limited */
    rq->cpu_seconds = 0;
    b->budget = rq->budget;
    pthread_mutex_init(&b->lock, NULL);
    pthread_cond_init(&b->idle, NULL);
    /* two readers a thread: one decoding for a read while another decodes
     * ahead (store_prefetch) */
    const int nr = 2 * vv_threads_get();
    b->n = nr < 1 ? 1 : nr > SBX_MAX_READERS ? SBX_MAX_READERS : nr;
    for (int i = 0; i < b->n; i++)
        b->rd[i] = (sbx_reader){-1, -1, RD_IDLE, 0, {0, 0, 0}, NULL, 0};
    st->ctx = b;
    st->close = store_close;
    st->read_chunk = store_read_chunk;
    st->prefetch = store_prefetch;
    st->parallel = 1; /* a reader a thread */
    s = store_start(b, exe, rq, info);
    free(rq);
    if (s != VV_OK)
        return s;
    const sbx_store_head *h = &b->head;
    st->n_levels = h->n_levels;
    st->n_channels = h->n_channels;
    st->n_times = h->n_times;
    st->has_range = h->has_range;
    memcpy(st->range, h->range, sizeof st->range);
    for (int l = 0; l < h->n_levels && s == VV_OK; l++) {
        s = vv_pyr_store_level(st, l, (vv_voxel_type)h->lv[l].type, h->lv[l].dims, h->lv[l].cdims);
        if (s == VV_OK) {
            vv_volume *v = st->lv[l].hdr;
            memcpy(v->spacing, h->lv[l].spacing, sizeof v->spacing);
            memcpy(v->origin, h->lv[l].origin, sizeof v->origin);
            v->unit = (vv_unit)h->lv[l].unit;
            v->modification = VV_MOD_ORIGINAL;
        }
    }
    return s;
}

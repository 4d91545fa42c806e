/*
 * The reader's lockdown (src/sandbox; docs/security.md, "The reader
 * sandbox"): what volvis-reader does to itself before it touches the file.
 * Landlock: read access beneath the input's folder only (and the memory
 * cgroup's files the budget reads), no TCP, no signals or abstract sockets
 * outside. seccomp: the system calls a reader needs to read files,
 * compute with threads and hand back its result; everything else ends the
 * process (SIGSYS). Resource limits: no core file, CPU seconds, address
 * space from the memory budget.
 */
#define _GNU_SOURCE
#include <errno.h>
#include <fcntl.h>
#include <linux/landlock.h>
#include <sched.h>
#include <seccomp.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/file.h>
#include <sys/mman.h>
#include <sys/prctl.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/syscall.h>
#include <unistd.h>

#include "core/internal.h"
#include "sandbox/sandbox_internal.h"

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

/* The coverage build's profile runtime (clang's -fprofile-instr-generate,
 * the coverage presets): weak, so absent from every other build. */
void __llvm_profile_set_file_object(FILE *file, int merge) __attribute__((weak));
void __llvm_profile_set_dumped(void) __attribute__((weak));

void
sbx_profile_before_lockdown(void) {
    if (!__llvm_profile_set_file_object)
        return;
    /* the profile is written at exit, after the lockdown, which allows
     * neither creating the file nor locking it: open it now, beside the
     * ones $LLVM_PROFILE_FILE names, else write none */
    const char *pattern = getenv("LLVM_PROFILE_FILE");
    const char *slash = pattern ? strrchr(pattern, '/') : NULL;
    FILE *f = NULL;
    if (slash) {
        char name[4096];
        snprintf(name, sizeof name, "%.*s/reader-%ld.profraw", (int)(slash - pattern), pattern,
                 (long)getpid());
        f = fopen(name, "wb");
    }
    if (f)
        __llvm_profile_set_file_object(f, 0);
    else if (__llvm_profile_set_dumped)
        __llvm_profile_set_dumped();
}

/* Read access beneath each of the @p nd folders @p dirs (opened with
 * O_PATH | @p flags; the first @p required of them must open, the others
 * may be missing) added to ruleset @p rs, which then restricts this
 * process; @p rs is closed. Returns 0, or -1 with errno. */
static int
restrict_reads(int rs, char (*dirs)[SBX_MAX_PATH], int nd, int flags, int required) {
    int ok = 1;
    for (int i = 0; i < nd && ok; i++) {
        struct landlock_path_beneath_attr pb = {0};
        pb.allowed_access = LANDLOCK_ACCESS_FS_READ_FILE | LANDLOCK_ACCESS_FS_READ_DIR;
        pb.parent_fd = open(dirs[i], O_PATH | O_CLOEXEC | flags);
        if (pb.parent_fd < 0) {
            ok = i >= required;
            continue;
        }
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

/* The file-system accesses Landlock's ABI @p abi handles: all it knows. */
static uint64_t
handled_fs(long abi) {
    return abi >= 5 ? 0xffffULL : abi >= 3 ? 0x7fffULL : abi >= 2 ? 0x3fffULL : 0x1fffULL;
}

/* A first Landlock layer from $VOLVIS_SANDBOX_BENEATH (a folder: `volvis
 * serve` sets its --root): reads beneath it (and the memory cgroup's
 * files) only, whatever path the request names. Layers intersect, so the
 * input folder's layer below can only narrow it: a link swapped into the
 * root after the server's check cannot make a reader read outside the
 * root. Returns 0 (also when unset), or -1 with errno. */
static int
beneath_layer(uint64_t handled) {
    const char *root = getenv("VOLVIS_SANDBOX_BENEATH");
    if (!root || !root[0])
        return 0;
    struct sbx_landlock_ruleset_attr ra = {0};
    ra.handled_access_fs = handled;
    int rs = (int)syscall(SYS_landlock_create_ruleset, &ra, sizeof(uint64_t), 0);
    if (rs < 0)
        return -1;
    char dirs[2][SBX_MAX_PATH];
    int nd = 0;
    snprintf(dirs[nd++], sizeof dirs[0], "%s", root);
    if (vv_memory_cgroup_root(dirs[nd], sizeof dirs[nd]))
        nd++;
    return restrict_reads(rs, dirs, nd, O_DIRECTORY, 1);
}

/* Read access beneath the folder of @p path (the folder itself when it is
 * one) and nothing else on any file system; no TCP; no signals to or
 * abstract sockets of processes outside. With $VOLVIS_SANDBOX_BENEATH, a
 * layer beneath that folder first (beneath_layer). Returns 0, or -1 with
 * errno (the kernel has no Landlock: ENOSYS or EOPNOTSUPP). */
int
sbx_landlock_restrict(const char *path) {
    long abi = syscall(SYS_landlock_create_ruleset, NULL, 0, LANDLOCK_CREATE_RULESET_VERSION);
    if (abi < 1)
        return -1;
    if (beneath_layer(handled_fs(abi)) != 0)
        return -1;
    struct sbx_landlock_ruleset_attr ra = {0};
    ra.handled_access_fs = handled_fs(abi);
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
    return restrict_reads(rs, dirs, nd, 0, 0);
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

int
sbx_seccomp_restrict(void) {
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

/* The reader's address-space limit: the voxels and a copy of them (the
 * memory budget twice), the libraries' own buffers and the executable's
 * mappings (1 GiB), a thread stack and a malloc arena per thread. */
uint64_t
sbx_address_limit(uint64_t budget, int threads) {
    return 2 * budget + ((uint64_t)1 << 30) + (uint64_t)(threads > 0 ? threads : 1) * (72u << 20);
}

/* The limits of the reader: no core file; CPU seconds; address space from
 * the memory budget (not under a sanitizer, whose shadow memory is
 * terabytes of address space); not dumpable, unless @p peek: its parent
 * then copies the voxels out of it (process_vm_readv, which the kernel
 * refuses for a process that is not dumpable unless the caller may
 * ptrace anything); a core file is still never written. */
void
sbx_set_limits(uint64_t budget, int threads, unsigned cpu_seconds, int peek) {
    struct rlimit no_core = {0, 0};
    setrlimit(RLIMIT_CORE, &no_core);
    struct rlimit cpu = {cpu_seconds, (rlim_t)cpu_seconds + 5};
    if (cpu_seconds > 0) /* 0: a long-lived reader, timed request by request */
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
    uint64_t as = sbx_address_limit(budget, threads);
    struct rlimit r_as = {(rlim_t)as, (rlim_t)as};
    setrlimit(RLIMIT_AS, &r_as);
#else
    (void)budget;
    (void)threads;
#endif
    if (!peek)
        prctl(PR_SET_DUMPABLE, 0, 0, 0, 0);
}

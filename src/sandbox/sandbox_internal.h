/*
 * The reader sandbox's wire and its shared pieces, internal to src/sandbox
 * (include/volvis/sys/sandbox.h is its face).
 *
 * The protocol, over a SOCK_SEQPACKET socket pair on the reader's
 * descriptor 3 (each message whole or not at all): the reader first says
 * hello (sbx_hello: its protocol version and sbx_layout(), a fingerprint
 * of its structures; the hello's own layout no version changes);
 * the parent sends one sbx_request; the reader answers with an sbx_reply
 * of kind SBX_FORMAT once it knows the row it reads with (so that a crash
 * can be named after its reader) and one of kind SBX_RESULT, which carries
 * the memfd of its result (SCM_RIGHTS) when the read succeeded. A volume
 * asked with peek (the parent found it may read the reader's memory) comes
 * without a memfd: the reply names where the voxels lie in the reader, the
 * parent copies them out (process_vm_readv) and only then stops the
 * reader, which waits for it. A store's
 * reader then answers one sbx_box after another. The parent trusts
 * nothing in a reply: sizes are checked against the memfd, the memfd must
 * be sealed, geometry must be finite, and the value range is computed
 * again.
 *
 *   client.c   the parent: finding and starting the reader, one call
 *   store.c    the parent's side of a store's long-lived readers
 *   server.c   the reader: the request, the lockdown, the handlers
 *   policy.c   the lockdown: Landlock, seccomp, resource limits
 *   payload.c  results in sealed memfds: the reader's encoders (and its
 *              memfd allocator), the parent's checked decoders
 */
#ifndef VV_SANDBOX_INTERNAL_H
#define VV_SANDBOX_INTERNAL_H

#include <stddef.h>
#include <stdint.h>
#include <sys/types.h>

#include "volvis/sys/sandbox.h"

#define SBX_MAGIC 0x56565342u /* "VVSB" */
#define SBX_FD 3
#define SBX_MAX_PATH 4096
#define SBX_MAX_ERROR 4096
#define SBX_MAX_BOX_BYTES ((uint64_t)1 << 30)
#define SBX_MAX_LIST_BYTES ((uint64_t)1 << 32)

/** The kinds of the reader's messages. */
enum { SBX_FORMAT = 1, SBX_RESULT = 2, SBX_HELLO = 3 };

/** Test-only misbehaviour of the reader (VOLVIS_SANDBOX_INJECT), after it is
 *  locked down: what a hostile or broken parser would do. */
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
#define SBX_N_INJECT 12
extern const char *const sbx_inject_names[SBX_N_INJECT];

/** The reader's first message: a layout no protocol changes. */
typedef struct sbx_hello {
    uint32_t magic;
    int32_t kind; /* SBX_HELLO */
    uint32_t version;
    uint32_t layout; /* sbx_layout(): 0 from readers before it */
} sbx_hello;

/** The parent's request. */
typedef struct sbx_request {
    uint32_t magic, version;
    int32_t op; /* vv_sandbox_op */
    char format[VV_SANDBOX_NAME_MAX];
    uint64_t budget; /* the memory budget (vv_memory_budget_set) */
    int32_t threads;
    int32_t inject;
    int32_t peek;         /* a volume: keep the voxels in the reader's memory (sbx_reply.addr) */
    uint32_t cpu_seconds; /* 0: a long-lived reader, timed request by request */
    uint32_t args_len;
    unsigned char args[VV_SANDBOX_ARGS_MAX];
    uint32_t path_len;
    char path[SBX_MAX_PATH];
} sbx_request;

/** A chunk asked of a store's reader: chunk c (chunk indices along x, y, z) of a level. */
typedef struct sbx_box {
    uint32_t magic;
    int32_t level, c[3];
} sbx_box;

/**
 * A message of the reader to the parent (sent whole, of
 * offsetof(sbx_reply, err) + err_len bytes): kind SBX_FORMAT names the
 * row it reads with; kind SBX_RESULT ends the read with a status (a
 * vv_status) and the error trace in err, and on success carries a sealed
 * memfd of @c bytes bytes: for a volume its voxels (x fastest; the
 * geometry in the fields), for a listing its bytes, for a mesh n_vertices
 * positions (3 float32 each, world units) then n_triangles triangles (3
 * uint32 vertex indices each), for a grid the sections of sbx_grid_head,
 * for a store its window (sbx_store_head first).
 */
typedef struct sbx_reply {
    uint32_t magic;
    int32_t kind;
    int32_t status;
    char format[VV_SANDBOX_NAME_MAX], title[64];
    int32_t dims[3];
    int32_t type;
    double spacing[3], origin[3], direction[9];
    int32_t unit, data_origin, modification, space;
    uint32_t info_len;
    unsigned char info[VV_SANDBOX_INFO_MAX];
    uint64_t bytes;
    uint64_t addr; /* a volume asked with peek: where its voxels are in the reader (no memfd) */
    uint64_t n_vertices, n_triangles; /* a mesh: positions then triangles */
    uint64_t file_bytes;              /* a store's chunk: bytes read from storage */
    int32_t missing;                  /* a store's chunk: absent, the fill value */
    uint32_t err_len;
    char err[SBX_MAX_ERROR];
} sbx_reply;

/** One level of a store as its reader sends it (sbx_store_head). */
typedef struct sbx_level {
    int32_t dims[3], cdims[3], type, unit;
    double spacing[3], origin[3], direction[9];
} sbx_level;

/** A store's table, at the start of its window. */
typedef struct sbx_store_head {
    int32_t n_levels, n_channels, n_times, has_range;
    double range[2];
    sbx_level lv[VV_STORE_MAX_LEVELS];
} sbx_store_head;

/**
 * A grid in the reader's memfd: this head, then, each section starting on
 * a multiple of 8 bytes: the points (3 * n_points double, world units),
 * the cell types (n_cells bytes), the cell offsets (n_cells + 1 uint64),
 * the connectivity (n_conn uint32), the block dimensions (n_blocks * 3
 * int32), the spherical axes (sph_dims[0] + sph_dims[1] + sph_dims[2]
 * double: r, theta, phi), then n_fields times an sbx_grid_field and its
 * n_tuples * n_components float values.
 */
typedef struct sbx_grid_head {
    int32_t kind; /* vv_grid_kind */
    int32_t n_fields, n_blocks;
    int32_t sph_dims[3];
    uint64_t n_points, n_cells, n_conn;
} sbx_grid_head;

/** A field's head in a grid's memfd (see sbx_grid_head). */
typedef struct sbx_grid_field {
    char name[VV_GRID_FIELD_NAME_MAX];
    int32_t cell_data, n_components, has_fill, pad;
    double fill;
    uint64_t n_tuples;
} sbx_grid_field;

/* ---- shared ---- */

/** madvise(@p advice) over [@p p, @p p + @p len) in 8 MiB pieces on the library's threads. */
void sbx_madvise_parallel(void *p, size_t len, int advice);
/** The reader's address-space limit for a memory budget and thread count. */
uint64_t sbx_address_limit(uint64_t budget, int threads);
/** Bytes rounded up to a multiple of 8 (the grid memfd's sections). */
static inline uint64_t
sbx_pad8(uint64_t n) {
    return (n + 7) & ~(uint64_t)7;
}
/** @p s as one line of printable text, in place (NUL-terminated within @p cap). */
void sbx_printable(char *s, size_t cap);

/* ---- policy.c (the reader) ---- */

/** No core file; CPU seconds; address space from the budget (not under a sanitizer); not
 *  dumpable unless @p peek (the parent then copies the voxels out of this process). */
void sbx_set_limits(uint64_t budget, int threads, unsigned cpu_seconds, int peek);
/** Read access beneath the folder of @p path only; 0, or -1 with errno. */
int sbx_landlock_restrict(const char *path);
/** The reader's system-call filter; 0 or -1. */
int sbx_seccomp_restrict(void);

/* Coverage builds only (clang's profile runtime linked in): opens the
 * reader's profile file before the lockdown, which would forbid creating
 * it at exit (beside $LLVM_PROFILE_FILE's, as reader-PID.profraw; none
 * written when that names no folder). Does nothing in other builds. */
void sbx_profile_before_lockdown(void);

/* ---- payload.c ---- */

/** The reader's volume allocator: voxels in memfds (vv_volume_set_allocator). */
void *sbx_memfd_alloc(size_t bytes);
void sbx_memfd_release(void *user, void *data);
/** The memfd holding @p data (a copy into a new one when it was made otherwise); -1 on failure. */
int sbx_memfd_of(void *data, size_t bytes);
/** @p fd sealed for handing over (the reader's mapping removed first, so that it can be
 *  sealed against writing too), or -1 (then closed); @p scribble: seals against resizing
 *  only and keeps the mapping (the test's hostile reader). */
int sbx_sealed(int fd, int scribble);
/** A new memfd holding a copy of @p m (positions, triangles); -1 on failure. */
int sbx_mesh_memfd(const vv_mesh *m, uint64_t *bytes);
/** A new memfd holding @p g as sbx_grid_head lays it out; -1 on failure. */
int sbx_grid_memfd(const vv_grid *g, uint64_t *bytes);

/** The parent's checked decoders; each owns @p fd (closed or mapped and closed). A
 * volume's value range is measured here, over the mapped voxels, in the pass that
 * populates the mapping (no range a reader sends is trusted). */
vv_status sbx_volume_from_reply(vv_volume **out, const sbx_reply *r, int fd, const char *name,
                                const char *file);
/** The volume of a peek reply: r->bytes copied out of reader @p peer at r->addr (see
 *  sbx_take_message_peer). */
vv_status sbx_volume_from_peer(vv_volume **out, const sbx_reply *r, pid_t peer, const char *name,
                               const char *file);
vv_status sbx_mesh_from_reply(vv_mesh **out, const sbx_reply *r, int fd, const char *name,
                              const char *file);
vv_status sbx_grid_from_reply(vv_grid **out, const sbx_reply *r, int fd, const char *name,
                              const char *file);
vv_status sbx_blob_from_reply(void **out, size_t *len, const sbx_reply *r, int fd, const char *name,
                              const char *file);

/**
 * What the parent makes of one message @p msg of @p len bytes (untrusted)
 * of a reader asked for @p op, with @p fd the descriptor it carried or -1
 * (owned). Returns 0 when more is to come (a format message: @p name and
 * @p title take the row it names, when printable), 1 for the result (*@p out
 * filled; *@p status its status, set with vv_error_set), -1 when malformed.
 * Fuzzed by tests/fuzz/fuzz_sandbox.c. A volume reply that names an
 * address instead of carrying a memfd is refused ("no voxels").
 */
int sbx_take_message(int op, const void *msg, size_t len, int fd, char name[VV_SANDBOX_NAME_MAX],
                     char title[64], const char *file, vv_sandbox_result *out, vv_status *status);
/**
 * sbx_take_message for a request sent with peek to reader @p peer (> 0; 0:
 * none): a volume reply may then name an address (sbx_reply.addr, no
 * memfd), whose r->bytes the parent copies out of @p peer's memory into a
 * volume of its own (process_vm_readv, 4 MiB pieces on the library's
 * threads, the range measured on the copy as each piece lands: nothing the
 * reader changes afterwards reaches it). Errors: an address the copy
 * cannot read whole, VV_ERR_FORMAT; no memory for the volume, VV_ERR_NOMEM.
 */
int sbx_take_message_peer(int op, const void *msg, size_t len, int fd, pid_t peer,
                          char name[VV_SANDBOX_NAME_MAX], char title[64], const char *file,
                          vv_sandbox_result *out, vv_status *status);
/**
 * 1 when this process may copy memory out of reader @p pid
 * (process_vm_readv: the kernel's ptrace access check, a reader still
 * dumpable), 0 when not (Yama, another user, no such call): asked once a
 * process with a one-byte read at an unmapped address, which fails with
 * EFAULT only once access is granted. VOLVIS_SANDBOX_PEEK=0 forces 0.
 */
int sbx_can_peek(pid_t pid);

/** The bytes of a store's window (payload.c): its table, or its largest
 *  chunk; 0 when a chunk is over SBX_MAX_BOX_BYTES. */
uint64_t sbx_window_bytes(const sbx_store_head *h);

/**
 * A fingerprint of the wire's layout (the sizes of the request, the
 * replies, a store's head and box, the room for info bytes), sent in the
 * hello: a reader of the same protocol version but another build whose
 * structures differ (a stale /usr/local/libexec/volvis-reader found before
 * this build's) is refused by name before any request, not misread. The
 * info bytes' own layout (io's vv_load_info, a layer above) is checked by
 * their size where io reads them (transport.c).
 */
uint32_t sbx_layout(void);

/* ---- client.c (the parent) ---- */

/** The reader to run into @p exe (PATH_MAX bytes), or an error naming @p name: FILE. */
vv_status sbx_reader_for(const char *name, const char *path, char *exe);
/** Starts a reader (a spare one when there is) on a new socket. 0 or an errno value. */
int sbx_take_reader(const char *exe, pid_t *pid, int *sock);
/** Starts a new reader. 0 or an errno value. */
int sbx_spawn_reader(const char *exe, pid_t *pid, int *sock);
/** Reaps @p pid later (its teardown need not delay the caller). */
void sbx_reap_later(pid_t pid);
/** A request for @p c (malloc'd; NULL: out of memory); @p cpu_seconds 0 for a store. */
sbx_request *sbx_new_request(const vv_sandbox_call *c);
/** Waits for the reader's hello on @p sock until @p deadline (seconds, sbx_now); VV_OK, or
 *  VV_ERR_IO naming @p exe and its protocol. */
vv_status sbx_hello_wait(int sock, double deadline, const char *exe, const char *name,
                         const char *file);
/** One message of a reader on @p sock: its length; 0 when the reader is gone, -1 when
 *  interrupted, -2 when cut (malformed). *passed: the descriptor it carried or -1. */
ssize_t sbx_recv(int sock, void *buf, size_t cap, int *passed);
/** The one line for a reader that ended without a result. */
vv_status sbx_describe_end(int status, uint64_t peak, uint64_t budget, const char *name,
                           const char *title, const char *file, unsigned limit, int timed_out);
/** Monotonic seconds. */
double sbx_now(void);
/** Seconds a reader may run on @p path: 60 plus one per 10 MB, or $VOLVIS_SANDBOX_TIMEOUT. */
unsigned sbx_time_limit(const char *path);

#endif

/*
 * The GPU ray caster's kernel (src/render/gpu/gpu.c): one invocation a
 * pixel, the CPU ray caster's method step for step (src/render/raycast,
 * ray.h, sample.h, shade.h, project.h) so that the images agree: the
 * world ray through the pixel centre mapped into the volume's index space
 * and clipped to its grid box and the cut planes; samples at t = k dt (world
 * units); trilinear values of the cached voxels (stored units); the
 * object's transfer-function table (opacity corrected for the step); unit
 * gradients from the cached octahedral codes, trilinearly interpolated (or
 * central differences of samples where none are cached); Phong with the
 * reflection vector, two-sided, with the World's lights; front-to-back
 * compositing with early ray termination; leaps over cubes of subvolumes
 * the transfer function hides (their chessboard distance); MIP and MinIP
 * with the table's flat ends and the subvolumes' min/max; the X-ray mean;
 * napari's attenuated MIP (project.c vv_vray_attenuated_mip, and by
 * regions vv_vray_attenuated_region_pixel); the first isosurface crossing
 * refined by ten bisections.
 * Levoy, "Display of Surfaces from Volume Data", IEEE CG&A 1988; the VolVis
 * paper, section 5 (volume ray casting) and section 4 (PARC subvolumes).
 */
#version 450

layout(local_size_x = 8, local_size_y = 8) in;

const int MODE_COMPOSITE = 0, MODE_MIP = 1, MODE_MINIP = 2, MODE_XRAY = 3, MODE_ISO = 4;
const int MODE_ATTENUATED_MIP = 5;
/* the frame's flags (misc.w) and a channel's (chf[ch].x) */
const int F_SHADING = 1, F_SKIPPING = 4, F_LUT2D = 32;
/* a region render: the opacity in front of it (Front); its rectangle alone dispatched */
const int F_FRONT = 64, F_RECT = 128;
const int F_NORMALS = 2, F_INTEGER = 16;
const int LUT2_V = 1024, LUT2_G = 128;
const int MAX_LIGHTS = 16, MAX_PLANES = 16, LUT = 4096, SPEC = 2048, BLOCK = 4, MAX_CH = 4;
const int BLEND_COMPOSITE = 0, BLEND_ADDITIVE = 1, BLEND_MAXIMUM = 2;

layout(std140, set = 0, binding = 0) uniform Frame {
    vec4 o00, ox, oy, d00, dx, dy; /* camera rays, affine in the pixel (xyz) */
    vec4 w2i[3];                   /* world -> index, rows */
    vec4 nrm[3];                   /* index-space gradient -> world normal, rows */
    vec4 amb;                      /* ka * ambient */
    vec4 bg;                       /* background (0 in a region render) */
    vec4 base;                     /* material colour (iso) */
    vec4 ldir[MAX_LIGHTS];         /* unit vector towards the light; w: 1 point light */
    vec4 lpos[MAX_LIGHTS];         /* point light position */
    vec4 kd[MAX_LIGHTS];           /* kd * light colour */
    vec4 ks[MAX_LIGHTS];           /* ks * light colour */
    vec4 planes[MAX_PLANES];       /* cut planes n.x + d >= 0 kept */
    ivec4 dims;                    /* cached grid nx, ny, nz; mode */
    ivec4 bdims;                   /* subvolumes bx, by, bz; lights */
    ivec4 misc;                    /* width, height, planes, flags */
    ivec4 clipd;                   /* the grid box [0, clipd - 1] */
    vec4 p0;                       /* dt, early termination, iso (stored units), 0 */
    vec4 rlo, rhi;                 /* a region's samples: rlo <= p < rhi (whole index space) */
    ivec4 roff;                    /* its voxels' offset in the whole volume; w: 1 region */
    ivec4 rect;                    /* pixels x0 <= x < x1, y0 <= y < y1 (x1 <= x0: all) */
    vec4 p2;                       /* 2-D TF: table index -> value bin, |gradient| -> bin */
    vec4 chp[MAX_CH];              /* per channel: table lo, table scale, value scale, MIP floor */
    vec4 chq[MAX_CH];              /* per channel: MIP stop */
    ivec4 chf[MAX_CH];             /* per channel: F_INTEGER | F_NORMALS */
    ivec4 chn;                     /* channels (0: one-channel object), blend rule */
    vec4 att;                      /* attenuated MIP: lo, inv_range, qoff, vmax (project.h) */
    vec4 attk;                     /* its k, a region's k step_scale, 1: early stop */
} fr;

layout(set = 0, binding = 1) uniform sampler3D vol;   /* stored values (R16 unorm or R32F) */
layout(set = 0, binding = 2) uniform isampler3D onrm; /* octahedral gradient codes (u, v) */
layout(std430, set = 0, binding = 3) readonly buffer Lut { vec4 lut[]; };
layout(std430, set = 0, binding = 4) readonly buffer Spec { float spec[]; };
layout(std430, set = 0, binding = 5) readonly buffer Dist { uint bdist[]; }; /* bytes */
layout(std430, set = 0, binding = 6) readonly buffer MinMax { vec2 bmm[]; };
layout(std430, set = 0, binding = 7) writeonly buffer Rgba { vec4 out_rgba[]; };
layout(std430, set = 0, binding = 8) writeonly buffer Depth { float out_depth[]; };
layout(std430, set = 0, binding = 9) writeonly buffer Key { float out_key[]; };
layout(set = 0, binding = 10) uniform sampler3D gmag; /* gradient magnitude per voxel */
layout(std430, set = 0, binding = 11) readonly buffer Lut2 { vec4 lut2[]; };
/* channels 1 .. 3 of a multi-channel object (channel 0: vol and onrm) */
layout(set = 0, binding = 12) uniform sampler3D vol1;
layout(set = 0, binding = 13) uniform sampler3D vol2;
layout(set = 0, binding = 14) uniform sampler3D vol3;
layout(set = 0, binding = 15) uniform isampler3D onrm1;
layout(set = 0, binding = 16) uniform isampler3D onrm2;
layout(set = 0, binding = 17) uniform isampler3D onrm3;
/* F_FRONT: per pixel (row-major, the whole view), the opacity composited in
 * front of this region (vv_render_region.front) */
layout(std430, set = 0, binding = 18) readonly buffer Front { float front_a[]; };

ivec3 gmax;   /* dims - 2: the last cell */
vec3 o_i;     /* index point at t = tb (the whole volume's index space) */
vec3 voff;    /* a region's voxel offset: its voxels' points are p - voff */
bool region;
vec3 d_i;     /* index direction per world unit */
vec3 inv_d;   /* 1 / d_i, 0 where d_i is 0 */
float tb;

/* voxel c of channel ch (0: a one-channel object's volume) in stored units */
float
voxel(int ch, ivec3 c) {
    float r = ch == 0   ? texelFetch(vol, c, 0).r
              : ch == 1 ? texelFetch(vol1, c, 0).r
              : ch == 2 ? texelFetch(vol2, c, 0).r
                        : texelFetch(vol3, c, 0).r;
    float v = r * fr.chp[ch].z;
    return (fr.chf[ch].x & F_INTEGER) != 0 ? round(v) : v;
}

ivec2
code_of(int ch, ivec3 c) {
    return ch == 0   ? texelFetch(onrm, c, 0).xy
           : ch == 1 ? texelFetch(onrm1, c, 0).xy
           : ch == 2 ? texelFetch(onrm2, c, 0).xy
                     : texelFetch(onrm3, c, 0).xy;
}

/* the point of ray parameter t in the voxels' index space (a region's
 * voxels start at voff: ray.h vv_vray_point) */
vec3
point_at(float t) {
    return (o_i + (t - tb) * d_i) - voff;
}

/* whether a region render owns sample t: rlo <= p < rhi (always outside
 * region renders) */
bool
owned(float t) {
    if (!region)
        return true;
    const vec3 p = o_i + (t - tb) * d_i;
    return all(greaterThanEqual(p, fr.rlo.xyz)) && all(lessThan(p, fr.rhi.xyz));
}

/* sample.h vv_vcache_cell_of: the cell (clamped so its far corner is in the
 * grid) and the fractions (at most 1) */
ivec3
cell_of(vec3 p, out vec3 f) {
    p = max(p, vec3(0));
    ivec3 i = min(ivec3(p), gmax);
    f = min(p - vec3(i), vec3(1));
    return i;
}

float
value_at(int ch, ivec3 i, vec3 f) {
    float c00 = mix(voxel(ch, i), voxel(ch, i + ivec3(1, 0, 0)), f.x);
    float c10 = mix(voxel(ch, i + ivec3(0, 1, 0)), voxel(ch, i + ivec3(1, 1, 0)), f.x);
    float c01 = mix(voxel(ch, i + ivec3(0, 0, 1)), voxel(ch, i + ivec3(1, 0, 1)), f.x);
    float c11 = mix(voxel(ch, i + ivec3(0, 1, 1)), voxel(ch, i + ivec3(1, 1, 1)), f.x);
    return mix(mix(c00, c10, f.y), mix(c01, c11, f.y), f.z);
}

float
sample_ch(int ch, vec3 p) {
    vec3 f;
    ivec3 i = cell_of(p, f);
    return value_at(ch, i, f);
}

float
sample_at(vec3 p) {
    return sample_ch(0, p);
}

vec3
oct_decode(int ch, ivec3 c) {
    ivec2 q = code_of(ch, c);
    if (q.x == -128)
        return vec3(0);
    float u = float(q.x), v = float(q.y);
    float z = 127.0 - abs(u) - abs(v);
    float t = max(-z, 0.0);
    vec3 n = vec3(u + (u >= 0.0 ? -t : t), v + (v >= 0.0 ? -t : t), z);
    return n / sqrt(dot(n, n));
}

/* sample.h vv_vcache_gradient: the cached unit gradients of the cell's
 * corners interpolated, or central differences half a voxel apart */
vec3
gradient_ch(int ch, vec3 p) {
    if ((fr.chf[ch].x & F_NORMALS) != 0) {
        vec3 f;
        ivec3 i = cell_of(p, f);
        vec3 c00 = mix(oct_decode(ch, i), oct_decode(ch, i + ivec3(1, 0, 0)), f.x);
        vec3 c10 = mix(oct_decode(ch, i + ivec3(0, 1, 0)), oct_decode(ch, i + ivec3(1, 1, 0)), f.x);
        vec3 c20 = mix(oct_decode(ch, i + ivec3(0, 0, 1)), oct_decode(ch, i + ivec3(1, 0, 1)), f.x);
        vec3 c30 = mix(oct_decode(ch, i + ivec3(0, 1, 1)), oct_decode(ch, i + ivec3(1, 1, 1)), f.x);
        return mix(mix(c00, c10, f.y), mix(c20, c30, f.y), f.z);
    }
    vec3 g;
    for (int a = 0; a < 3; a++) {
        vec3 e = vec3(0);
        e[a] = 0.5;
        g[a] = sample_ch(ch, p + e) - sample_ch(ch, p - e);
    }
    return g;
}

vec3
gradient(vec3 p) {
    return gradient_ch(0, p);
}

/* shade.h vv_vshade: Phong with the reflection vector, two-sided */
vec3
shade(vec3 g, vec3 pw, vec3 v, vec3 col, float alpha) {
    vec3 n = vec3(dot(fr.nrm[0].xyz, g), dot(fr.nrm[1].xyz, g), dot(fr.nrm[2].xyz, g));
    float len2 = dot(n, n);
    vec3 d = fr.amb.xyz, s = vec3(0);
    if (len2 > 1e-12) {
        float inv = 1.0 / sqrt(len2);
        float nv = dot(n, v) * inv;
        for (int l = 0; l < fr.bdims.w; l++) {
            vec3 L = fr.ldir[l].xyz;
            if (fr.ldir[l].w > 0.5) {
                L = fr.lpos[l].xyz - pw;
                float ll = sqrt(dot(L, L));
                if (!(ll > 0.0))
                    continue;
                L /= ll;
            }
            float ndl = dot(n, L) * inv;
            float ndv = ndl < 0.0 ? -nv : nv;
            ndl = abs(ndl);
            float rv = 2.0 * ndl * ndv - dot(L, v);
            float sp = rv > 0.0 ? spec[min(int(rv * float(SPEC) + 0.5), SPEC)] : 0.0;
            d += ndl * fr.kd[l].xyz;
            s += sp * fr.ks[l].xyz;
        }
    }
    return d * col + alpha * s;
}

/* sample.h vv_vcache_gmag: the voxels' gradient magnitudes, trilinearly */
float
gmag_at(vec3 p) {
    vec3 f;
    ivec3 i = cell_of(p, f);
    float c00 = mix(texelFetch(gmag, i, 0).r, texelFetch(gmag, i + ivec3(1, 0, 0), 0).r, f.x);
    float c10 = mix(texelFetch(gmag, i + ivec3(0, 1, 0), 0).r,
                    texelFetch(gmag, i + ivec3(1, 1, 0), 0).r, f.x);
    float c01 = mix(texelFetch(gmag, i + ivec3(0, 0, 1), 0).r,
                    texelFetch(gmag, i + ivec3(1, 0, 1), 0).r, f.x);
    float c11 = mix(texelFetch(gmag, i + ivec3(0, 1, 1), 0).r,
                    texelFetch(gmag, i + ivec3(1, 1, 1), 0).r, f.x);
    return mix(mix(c00, c10, f.y), mix(c01, c11, f.y), f.z);
}

/* classify.h vv_vextra_apply: the 2-D transfer function's entry (value x
 * gradient magnitude, Kniss et al. 2002) in place of the 1-D one */
vec4
entry2d(float v, vec3 p) {
    float li = clamp((v - fr.chp[0].x) * fr.chp[0].y, 0.0, float(LUT - 1));
    int vb = int(li * fr.p2.x + 0.5);
    int gb = clamp(int(gmag_at(p) * fr.p2.y + 0.5), 0, LUT2_G - 1);
    return lut2[gb * LUT2_V + vb];
}

/* channel ch's table entry of value v (stored units) */
vec4
entry_ch(int ch, float v) {
    float x = clamp((v - fr.chp[ch].x) * fr.chp[ch].y, 0.0, float(LUT - 1));
    return lut[ch * LUT + int(x)];
}

vec4
entry(float v) {
    return entry_ch(0, v);
}

uint
block_of(vec3 p, out uvec3 bc) {
    bc = min(uvec3(ivec3(max(p, vec3(0)) * 0.25)), uvec3(fr.bdims.xyz - 1));
    return (bc.z * uint(fr.bdims.y) + bc.y) * uint(fr.bdims.x) + bc.x;
}

/* channel ch's subvolume b's distance to the nearest visible one */
uint
dist_ch(int ch, uint b) {
    const uint i = uint(ch) * uint(fr.bdims.x * fr.bdims.y * fr.bdims.z) + b;
    return (bdist[i >> 2] >> (8u * (i & 3u))) & 255u;
}

uint
dist_of(uint b) {
    return dist_ch(0, b);
}

/* ray.h vv_vray_leap: the sample index after the empty cube of 2 dist - 1
 * subvolumes around bc */
float
leap(vec3 p, float t, uvec3 bc, uint dist, float inv_dt, float k) {
    float te = 1.0 / 0.0;
    for (int a = 0; a < 3; a++) {
        if (inv_d[a] == 0.0)
            continue;
        float bound = d_i[a] > 0.0 ? float(int(bc[a]) + int(dist)) * float(BLOCK)
                                   : float(int(bc[a]) - int(dist) + 1) * float(BLOCK);
        te = min(te, (bound - p[a]) * inv_d[a]);
    }
    return max(ceil((t + te) * inv_dt), k + 1.0);
}

/* ray.h vv_vray_cube_exit: where the ray leaves the subvolume holding p */
float
block_exit(vec3 p, float t) {
    float te = 1.0 / 0.0;
    for (int a = 0; a < 3; a++) {
        if (inv_d[a] == 0.0)
            continue;
        float b = max(float(int(p[a] * 0.25)), 0.0);
        float bound = (d_i[a] > 0.0 ? b + 1.0 : b) * float(BLOCK);
        te = min(te, (bound - p[a]) * inv_d[a]);
    }
    return t + te;
}

float
iso_refine(float ta, float va, float tbb, float iso) {
    for (int it = 0; it < 10; it++) {
        float tm = 0.5 * (ta + tbb);
        float vm = sample_at(point_at(tm));
        if ((va < iso) == (vm < iso)) {
            ta = tm;
            va = vm;
        } else {
            tbb = tm;
        }
    }
    return 0.5 * (ta + tbb);
}

void
main() {
    const ivec2 px = ivec2(gl_GlobalInvocationID.xy) +
                     ((fr.misc.w & F_RECT) != 0 ? fr.rect.xy : ivec2(0));
    if (px.x >= fr.misc.x || px.y >= fr.misc.y)
        return;
    const uint at = uint(px.y) * uint(fr.misc.x) + uint(px.x);
    const float INF = 1.0 / 0.0;
    const float NAN = uintBitsToFloat(0x7fc00000u);
    region = fr.roff.w != 0;
    voff = region ? vec3(fr.roff.xyz) : vec3(0);
    if (fr.rect.z > fr.rect.x &&
        (px.x < fr.rect.x || px.x >= fr.rect.z || px.y < fr.rect.y || px.y >= fr.rect.w)) {
        out_rgba[at] = vec4(0);
        out_depth[at] = INF;
        out_key[at] = NAN;
        return;
    }
    /* early ray termination carried across regions: the ray ends once the
     * opacity in front (af) and this region's (A) reach the threshold,
     * af + (1 - af) A >= et, as the whole render's ray ends; a pixel
     * already that opaque takes no sample here */
    float et_ray = fr.p0.y;
    if ((fr.misc.w & F_FRONT) != 0) {
        const float af = front_a[at];
        if (af >= et_ray) {
            out_rgba[at] = vec4(0);
            out_depth[at] = INF;
            out_key[at] = NAN;
            return;
        }
        et_ray = (et_ray - af) / (1.0 - af);
    }
    float key = NAN;
    gmax = fr.dims.xyz - 2;
    const vec3 o = fr.o00.xyz + float(px.x) * fr.ox.xyz + float(px.y) * fr.oy.xyz;
    const vec3 dir = normalize(fr.d00.xyz + float(px.x) * fr.dx.xyz + float(px.y) * fr.dy.xyz);
    const int mode = fr.dims.w, flags = fr.misc.w;
    vec3 C = vec3(0);
    float A = 0.0, depth = INF;
    vec3 P = vec3(0);
    float PA = 0.0, pdepth = INF;

    /* the ray in index space, clipped to the grid box and the cut planes */
    vec3 oi, di;
    for (int a = 0; a < 3; a++) {
        oi[a] = dot(fr.w2i[a].xyz, o) + fr.w2i[a].w;
        di[a] = dot(fr.w2i[a].xyz, dir);
    }
    float t0 = 0.0, t1 = INF;
    bool hit = true;
    for (int a = 0; a < 3; a++) {
        const float hi = float(fr.clipd[a] - 1);
        if (abs(di[a]) < 1e-30) {
            hit = hit && oi[a] >= 0.0 && oi[a] <= hi;
            continue;
        }
        float ta = (0.0 - oi[a]) / di[a], tb2 = (hi - oi[a]) / di[a];
        t0 = max(t0, min(ta, tb2));
        t1 = min(t1, max(ta, tb2));
    }
    for (int q = 0; q < fr.misc.z && hit; q++) {
        const float dn = dot(fr.planes[q].xyz, dir);
        const float s0 = dot(fr.planes[q].xyz, o) + fr.planes[q].w;
        if (dn == 0.0) {
            hit = s0 >= 0.0;
            continue;
        }
        const float t = -s0 / dn;
        if (dn > 0.0)
            t0 = max(t0, t);
        else
            t1 = min(t1, t);
    }
    hit = hit && t0 <= t1;
    /* a region render: the stretch of the ray near its box (one voxel
     * wider), whose samples it then tests one by one (owned) */
    float ra = t0, rb = t1;
    if (hit && region) {
        for (int a = 0; a < 3; a++) {
            if (abs(di[a]) < 1e-30)
                continue;
            const float lo = fr.rlo[a] - 1.0, hi = fr.rhi[a] + 1.0;
            const float ta = (lo - oi[a]) / di[a], tb2 = (hi - oi[a]) / di[a];
            ra = max(ra, min(ta, tb2));
            rb = min(rb, max(ta, tb2));
        }
    }
    bool xsum = false;          /* a region's X-ray sum (key, remainder, count) */
    float xs = 0.0, xr = 0.0, xn = 0.0, xdepth = INF;
    bool asum = false;          /* a region's attenuated maximum (key, exponent sum) */
    float am = NAN, ae = 0.0, adepth = INF;
    if (hit) {
        tb = t0;
        o_i = oi + t0 * di;
        d_i = di;
        for (int a = 0; a < 3; a++)
            inv_d[a] = abs(di[a]) < 1e-30 ? 0.0 : 1.0 / di[a];
        const float dt = fr.p0.x, inv_dt = 1.0 / dt;
        const vec3 v = -dir;
        const bool skipping = (flags & F_SKIPPING) != 0;
        const int nch = fr.chn.x, blend = fr.chn.y;
        if (nch > 0 && blend != BLEND_MAXIMUM) {
            /* a multi-channel object (raycast.c trace_channels): composite,
             * the channels mixed per sample (Kniss et al. 2003); additive,
             * each composited on its own, the colours added */
            vec3 Cc[MAX_CH];
            float Ac[MAX_CH];
            for (int ch = 0; ch < MAX_CH; ch++) {
                Cc[ch] = vec3(0);
                Ac[ch] = 0.0;
            }
            const bool additive = blend == BLEND_ADDITIVE;
            const float et = et_ray;
            float k = ceil(t0 * inv_dt);
            float kend = floor(t1 * inv_dt);
            if (region) { /* the composite rule by regions: the region's samples */
                k = max(k, ceil(ra * inv_dt));
                kend = min(kend, floor(rb * inv_dt));
            }
            int live = additive ? nch : 1;
            while (k <= kend && live > 0) {
                const float t = k * dt;
                const vec3 p = point_at(t);
                uvec3 bc;
                const uint b = block_of(p, bc);
                uint dist = 255u;
                for (int ch = 0; ch < nch; ch++)
                    if (Ac[additive ? ch : 0] < et)
                        dist = min(dist, dist_ch(ch, b));
                if (skipping && dist > 0u) {
                    k = leap(p, t, bc, dist, inv_dt, k);
                    continue;
                }
                k += 1.0;
                if (!owned(t))
                    continue;
                float T = 1.0, sum_a = 0.0;
                vec3 col = vec3(0);
                for (int ch = 0; ch < nch; ch++) {
                    if (dist_ch(ch, b) != 0u || Ac[additive ? ch : 0] >= et)
                        continue;
                    const vec4 e = entry_ch(ch, sample_ch(ch, p));
                    if (e.x <= 0.0)
                        continue;
                    vec3 one = e.yzw;
                    if ((flags & F_SHADING) != 0)
                        one = shade(gradient_ch(ch, p), o + t * dir, v, e.yzw, e.x);
                    if (depth == INF)
                        depth = t;
                    if (additive) {
                        const float w = 1.0 - Ac[ch];
                        Cc[ch] += w * one;
                        Ac[ch] += w * e.x;
                        live -= Ac[ch] >= et ? 1 : 0;
                        continue;
                    }
                    col += one;
                    sum_a += e.x;
                    T *= 1.0 - e.x;
                }
                if (!additive && sum_a > 0.0) {
                    const float a = 1.0 - T, w = 1.0 - Ac[0];
                    Cc[0] += w * (a / sum_a) * col;
                    Ac[0] += w * a;
                    live = Ac[0] < et ? 1 : 0;
                }
            }
            float Tt = 1.0;
            for (int ch = 0; ch < (additive ? nch : 1); ch++) {
                C += Cc[ch];
                Tt *= 1.0 - min(Ac[ch], 1.0);
            }
            A = additive ? 1.0 - Tt : min(Ac[0], 1.0);
        } else if (nch > 0) {
            /* the maximum rule: a MIP per channel, each coloured by its
             * table, the colours added (raycast.c trace_channels_maximum) */
            float k = ceil(t0 / dt);
            const float kend = floor(t1 / dt);
            float best[MAX_CH], tbest[MAX_CH];
            for (int ch = 0; ch < MAX_CH; ch++) {
                best[ch] = fr.chp[ch].w;
                tbest[ch] = t0;
            }
            if (k > kend) {
                const float tm = 0.5 * (t0 + t1);
                for (int ch = 0; ch < nch; ch++) {
                    best[ch] = sample_ch(ch, point_at(tm));
                    tbest[ch] = tm;
                }
            }
            for (; k <= kend; k += 1.0) {
                const float t = k * dt;
                const vec3 p = point_at(t);
                bool more = false;
                for (int ch = 0; ch < nch; ch++) {
                    if (best[ch] >= fr.chq[ch].x)
                        continue;
                    more = true;
                    const float x = sample_ch(ch, p);
                    if (x > best[ch]) {
                        best[ch] = x;
                        tbest[ch] = t;
                    }
                }
                if (!more)
                    break;
            }
            float T = 1.0;
            for (int ch = 0; ch < nch; ch++) {
                const vec4 e = entry_ch(ch, best[ch]);
                P += e.yzw * e.x;
                T *= 1.0 - e.x;
                pdepth = min(pdepth, tbest[ch]);
            }
            PA = 1.0 - T;
        } else if (mode == MODE_COMPOSITE) {
            float k = ceil(t0 * inv_dt);
            float kend = floor(t1 * inv_dt);
            if (region) {
                k = max(k, ceil(ra * inv_dt));
                kend = min(kend, floor(rb * inv_dt));
            }
            const float et = et_ray;
            while (k <= kend) {
                const float t = k * dt;
                const vec3 p = point_at(t);
                if (skipping) {
                    uvec3 bc;
                    const uint dist = dist_of(block_of(p, bc));
                    if (dist > 0u) {
                        k = leap(p, t, bc, dist, inv_dt, k);
                        continue;
                    }
                }
                k += 1.0;
                if (!owned(t))
                    continue;
                const float val = sample_at(p);
                vec4 e = entry(val);
                if (e.x <= 0.0)
                    continue;
                if ((flags & F_LUT2D) != 0 && (e = entry2d(val, p)).x <= 0.0)
                    continue;
                vec3 col = e.yzw;
                if ((flags & F_SHADING) != 0)
                    col = shade(gradient(p), o + t * dir, v, e.yzw, e.x);
                const float w = 1.0 - A;
                C += w * col;
                A += w * e.x;
                if (depth == INF)
                    depth = t;
                if (A >= et)
                    break;
            }
            A = min(A, 1.0);
        } else if (mode == MODE_ISO) {
            const float iso = fr.p0.z;
            const float k0 = ceil(t0 / dt);
            float kend = floor(t1 / dt);
            float k = k0;
            if (region) {
                k = max(k, ceil(ra / dt));
                kend = min(kend, floor(rb / dt));
            }
            float pt = 0.0, pv = 0.0, th = -1.0;
            bool have = false;
            if (region) {
                /* the region's first sample; when it is not the ray's, the
                 * search starts at the one before it (project.h
                 * vv_vray_iso_first, cont) */
                while (k <= kend && !owned(k * dt))
                    k += 1.0;
                if (k <= kend && k > k0) {
                    pt = (k - 1.0) * dt;
                    pv = sample_at(point_at(pt));
                    have = true;
                    if (pv >= iso) {
                        th = pt;
                        k = kend + 1.0;
                    }
                }
            }
            while (k <= kend) {
                const float t = k * dt;
                const vec3 p = point_at(t);
                if (!owned(t))
                    break; /* past the region's samples */
                if (skipping) {
                    uvec3 bc;
                    const uint dist = dist_of(block_of(p, bc));
                    if (dist > 0u) {
                        k = leap(p, t, bc, dist, inv_dt, k);
                        have = false;
                        continue;
                    }
                }
                if (!have && k > k0) {
                    /* after hidden samples: restart at the one before */
                    pt = (k - 1.0) * dt;
                    pv = sample_at(point_at(pt));
                    have = true;
                }
                const float val = sample_at(p);
                if (!have) {
                    if (val >= iso && t - t0 < dt) {
                        th = t;
                        break;
                    }
                } else if ((pv < iso) != (val < iso)) {
                    th = iso_refine(pt, pv, t, iso);
                    break;
                }
                pv = val;
                pt = t;
                have = true;
                k += 1.0;
            }
            if (th >= 0.0) {
                const vec3 ph = point_at(th);
                vec3 col = fr.base.xyz;
                if ((flags & F_SHADING) != 0)
                    col = shade(gradient(ph), o + th * dir, v, fr.base.xyz, 1.0);
                C = col;
                A = 1.0;
                depth = th;
            }
        } else if (mode == MODE_ATTENUATED_MIP) {
            /* napari's attenuated MIP (VisPy's volume shader), as project.c
             * computes it: front to back, S the running sum of the samples'
             * contrast-normalised values n = clamp((v - lo) inv_range, 0, 1),
             * each real value v + qoff scaled by exp(-k (S - 1)), S
             * including the sample; the largest scaled value, classified as
             * MIP's maximum. Every sample is taken (no skipping). S is a
             * compensated float sum (project.c: a double). */
            const float lo = fr.att.x, inv_range = fr.att.y, qoff = fr.att.z, vmax = fr.att.w;
            const float ka = fr.attk.x;
            const float k0 = ceil(t0 / dt);
            float k = k0;
            float kend = floor(t1 / dt);
            const bool shortray = k > kend;
            if (region) {
                k = max(k, ceil(ra / dt));
                kend = min(kend, floor(rb / dt));
            }
            if (!region) {
                float value, tbest;
                if (shortray) {
                    /* one sample, in the middle: S is its own normalised value */
                    const float tm = 0.5 * (t0 + t1);
                    const float x = sample_at(point_at(tm));
                    const float n = clamp((x - lo) * inv_range, 0.0, 1.0);
                    const float f = ka == 0.0 ? 1.0 : exp(-ka * (n - 1.0));
                    value = x * f + qoff * (f - 1.0);
                    tbest = tm;
                } else {
                    float best = -INF;
                    precise float sum = 0.0, comp = 0.0; /* (not re-associated) */
                    tbest = k * dt;
                    const bool stop = fr.attk.z > 0.5;
                    for (; k <= kend; k += 1.0) {
                        const float t = k * dt;
                        const float x = sample_at(point_at(t));
                        const float n = clamp((x - lo) * inv_range, 0.0, 1.0);
                        precise const float y = n - comp; /* Kahan's sum */
                        precise const float sm = sum + y;
                        comp = (sm - sum) - y;
                        sum = sm;
                        /* (x + qoff) f - qoff, so that f == 1 gives x exactly */
                        const float f = ka == 0.0 ? 1.0 : exp(-ka * (sum - 1.0));
                        const float xs2 = x * f + qoff * (f - 1.0);
                        if (xs2 > best) {
                            best = xs2;
                            tbest = t;
                        }
                        /* every later sample is at most vmax, scaled by at most f */
                        if (stop && vmax * f + qoff * (f - 1.0) <= best)
                            break;
                    }
                    value = best;
                }
                const vec4 e = entry(value);
                P = e.yzw * e.x;
                PA = e.x;
                pdepth = tbest;
            } else {
                /* a region (VV_REGION_ATTENUATED_MAX): its exponents summed
                 * from 0, E = sum of k w n (w the region's step_scale); a
                 * sample's real value scaled by exp(k - E'), E' the samples'
                 * before it plus k n (itself counted once, as a sample of
                 * the finest level); the largest (real units) and E */
                const float ke = fr.attk.y;
                float best = -INF;
                precise float e = 0.0, comp = 0.0; /* (not re-associated) */
                bool any = false;
                for (float j = shortray ? 0.0 : k; j <= (shortray ? 0.0 : kend); j += 1.0) {
                    const float t = shortray ? 0.5 * (t0 + t1) : j * dt;
                    if (!owned(t))
                        continue;
                    any = true;
                    const float x = sample_at(point_at(t));
                    const float n = clamp((x - lo) * inv_range, 0.0, 1.0);
                    const float sc = ka == 0.0 ? 1.0 : exp(ka - (e + ka * n));
                    const float m = (x + qoff) * sc;
                    if (m > best) {
                        best = m;
                        adepth = t;
                    }
                    precise const float y = ke * n - comp; /* Kahan's sum */
                    precise const float sm = e + y;
                    comp = (sm - e) - y;
                    e = sm;
                }
                asum = true;
                if (any) {
                    am = best;
                    ae = e;
                }
            }
        } else {
            /* projections: MIP, MinIP, X-ray (project.h) */
            const float k0 = ceil(t0 / dt);
            float k = k0;
            float kend = floor(t1 / dt);
            const bool shortray = k > kend;
            if (region) {
                k = max(k, ceil(ra / dt));
                kend = min(kend, floor(rb / dt));
            }
            float value = 0.0;
            bool any = false;
            if (shortray) {
                /* one sample, in the middle */
                const float tm = 0.5 * (t0 + t1);
                any = owned(tm);
                value = sample_at(point_at(tm));
                pdepth = tm;
                xs = value;
                xn = 1.0;
                xdepth = tm;
            } else if (mode == MODE_XRAY) {
                float sum = 0.0, comp = 0.0, n = 0.0; /* Kahan's sum */
                for (; k <= kend; k += 1.0) {
                    if (!owned(k * dt))
                        continue;
                    if (n == 0.0 && k == k0)
                        xdepth = t0; /* the region holds the ray's first sample */
                    const float y = sample_at(point_at(k * dt)) - comp;
                    const float sm = sum + y;
                    comp = (sm - sum) - y;
                    sum = sm;
                    n += 1.0;
                }
                any = n > 0.0;
                value = any ? sum / n : 0.0;
                pdepth = t0;
                xs = sum;
                xr = -comp;
                xn = n;
            } else {
                const bool mip = mode == MODE_MIP;
                const float sg = mip ? 1.0 : -1.0;
                float best = mip ? fr.chp[0].w : -fr.chq[0].x;
                const float stop = mip ? fr.chq[0].x : -fr.chp[0].w;
                float tbest = t0;
                while (k <= kend && best < stop) {
                    const float t = k * dt;
                    const vec3 p = point_at(t);
                    if (skipping) {
                        uvec3 bc;
                        const vec2 mm = bmm[block_of(p, bc)];
                        if ((mip ? mm.y : -mm.x) <= best) {
                            if (owned(t))
                                any = true;
                            k = max(ceil(block_exit(p, t) * inv_dt), k + 1.0);
                            continue;
                        }
                    }
                    k += 1.0;
                    if (!owned(t))
                        continue;
                    any = true;
                    const float x = sg * sample_at(p);
                    if (x > best) {
                        best = x;
                        tbest = t;
                    }
                }
                value = sg * best;
                pdepth = tbest;
                if (region) {
                    /* a region that took no sample has no key; one that
                     * took only hidden ones may leave some untested:
                     * any owned sample on the stretch counts */
                    for (float j = max(ceil(t0 / dt), ceil(ra / dt));
                         !any && j <= min(floor(t1 / dt), floor(rb / dt)); j += 1.0)
                        any = owned(j * dt);
                }
            }
            if (!region || any) {
                const vec4 e = entry(value);
                P = e.yzw * e.x;
                PA = e.x;
                key = value; /* stored units, the same in every region */
            } else {
                pdepth = INF;
            }
            xsum = region && mode == MODE_XRAY;
            if (xsum && !any) {
                xs = 0.0;
                xn = 0.0;
                xdepth = INF;
            }
        }
    }
    if (asum) {
        /* VV_REGION_ATTENUATED_MAX: the largest attenuated value (real
         * units) as key, the exponents' sum in red; classified once the
         * regions are combined (vv_region_image_finish) */
        out_rgba[at] = vec4(ae, 0.0, 0.0, 0.0);
        out_depth[at] = adepth;
        out_key[at] = am;
        return;
    }
    if (xsum) {
        /* VV_REGION_SUM: the sum as key and remainder, the count; classified
         * once the regions' sums are added (vv_region_image_finish) */
        out_rgba[at] = vec4(xn > 0.0 ? xr : 0.0, xn, 0.0, 0.0);
        out_depth[at] = xdepth;
        out_key[at] = xn > 0.0 ? xs : NAN;
        return;
    }
    const float rest = 1.0 - A;
    const float A2 = A + rest * PA;
    out_rgba[at] = vec4(C + rest * P + (1.0 - A2) * fr.bg.xyz, A2);
    out_depth[at] = min(depth, pdepth);
    out_key[at] = key;
}

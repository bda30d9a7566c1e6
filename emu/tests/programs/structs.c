/*
 * structs.c - structures: copy, pass and return by value, arrays of
 * structures, nested structures, packed layouts and initialised data.
 *
 * Structure assignment of more than a few words compiles to a memcpy call
 * (EEPMOV.W in runtime.S); a structure returned by value goes through a
 * hidden pointer in ER0; a packed structure's 16/32-bit members at odd
 * offsets are read and written a byte at a time (the H8 cannot access a
 * word at an odd address). Only member values are printed - never sizes or
 * offsets of unpacked structures, which differ between host and target -
 * except for the packed one, whose size is the same everywhere.
 */
#include "testlib.h"

struct vec3 {
    i16 x, y, z;
};

struct particle {
    struct vec3 pos;
    struct vec3 vel;
    u8 id;
    i8 charge;
    u32 energy;
    char tag[6];
};

struct __attribute__((packed)) record {
    u8 kind;
    u32 stamp;
    i16 value;
    u8 flags;
    u16 crc;
};

struct big {
    u32 words[24];
};

/* Initialised, writable: lives in .data (copied from ROM by crt0). */
static struct particle swarm[6] = {
    { { 10, 20, 30 }, { 1, -1, 2 }, 1, -1, 1000u, "alpha" },
    { { -5, 0, 7 }, { -2, 3, -1 }, 2, 1, 2500u, "beta" },
    { { 100, -100, 50 }, { 0, 0, 1 }, 3, 0, 400u, "gamma" },
    { { 0, 0, 0 }, { 5, 5, 5 }, 4, -1, 0u, "delta" },
    { { -300, 200, -100 }, { 7, -7, 0 }, 5, 1, 123456u, "eps" },
    { { 32000, -32000, 1 }, { -1, 1, -1 }, 6, 0, 99u, "zeta" },
};

/* Initialised, read-only: lives in .rodata (ROM). */
static const struct vec3 directions[4] = {
    { 1, 0, 0 }, { 0, 1, 0 }, { -1, 0, 0 }, { 0, -1, 0 },
};

/* Zero-initialised: .bss (cleared by crt0). */
static struct big scratch;
static struct record log_buf[8];

static NOINLINE struct vec3 vec_add(struct vec3 a, struct vec3 b)
{
    struct vec3 r;
    r.x = (i16)(u16)((u16)a.x + (u16)b.x);
    r.y = (i16)(u16)((u16)a.y + (u16)b.y);
    r.z = (i16)(u16)((u16)a.z + (u16)b.z);
    return r;
}

static NOINLINE i32 vec_dot(const struct vec3 *a, const struct vec3 *b)
{
    return (i32)a->x * b->x + (i32)a->y * b->y + (i32)a->z * b->z;
}

/* Pass a large structure by value and return one by value. */
static NOINLINE struct particle particle_step(struct particle p, int dir)
{
    p.pos = vec_add(p.pos, p.vel);
    p.vel = vec_add(p.vel, directions[dir & 3]);
    p.energy += (u32)vec_dot(&p.vel, &p.vel);
    p.tag[0] = (char)(p.tag[0] ^ 0x20);
    return p;
}

static NOINLINE struct big big_fill(u32 seed)
{
    struct big b;
    int i;
    for (i = 0; i < 24; i++) {
        seed = seed * 1103515245u + 12345u;
        b.words[i] = seed;
    }
    return b;
}

static u32 big_sum(struct big b)
{
    u32 s = 0;
    int i;
    for (i = 0; i < 24; i++) {
        s = fold(s, b.words[i]);
    }
    return s;
}

static u32 particle_hash(const struct particle *p)
{
    u32 h = 0;
    int i;
    h = fold(h, (u32)(u16)p->pos.x << 16 | (u16)p->pos.y);
    h = fold(h, (u32)(u16)p->pos.z << 16 | (u16)p->vel.x);
    h = fold(h, (u32)(u16)p->vel.y << 16 | (u16)p->vel.z);
    h = fold(h, (u32)p->id << 8 | (u8)p->charge);
    h = fold(h, p->energy);
    for (i = 0; i < 6; i++) {
        h = fold(h, (u8)p->tag[i]);
    }
    return h;
}

static NOINLINE void record_write(struct record *r, u8 kind, u32 stamp, i16 value)
{
    r->kind = kind;
    r->stamp = stamp;
    r->value = value;
    r->flags = (u8)(kind ^ (u8)stamp);
    r->crc = (u16)(stamp ^ (stamp >> 16) ^ (u16)value);
}

static NOINLINE u32 record_read(const struct record *r)
{
    return fold(fold(fold(r->kind, r->stamp), (u32)(i32)r->value), (u32)r->flags << 16 | r->crc);
}

/* Insertion sort of structures by a key, swapping whole structures. */
static NOINLINE void sort_by_energy(struct particle *a, int n)
{
    int i, j;
    for (i = 1; i < n; i++) {
        struct particle key = a[i];
        j = i - 1;
        while (j >= 0 && a[j].energy > key.energy) {
            a[j + 1] = a[j];
            j--;
        }
        a[j + 1] = key;
    }
}

static void print_particle(const struct particle *p)
{
    con_puts(p->tag);
    con_puts(" id=");
    con_dec_u8(p->id);
    con_puts(" pos=");
    con_dec_i16(p->pos.x);
    con_putchar(',');
    con_dec_i16(p->pos.y);
    con_putchar(',');
    con_dec_i16(p->pos.z);
    con_puts(" vel=");
    con_dec_i16(p->vel.x);
    con_putchar(',');
    con_dec_i16(p->vel.y);
    con_putchar(',');
    con_dec_i16(p->vel.z);
    con_puts(" q=");
    con_dec_i8(p->charge);
    con_puts(" e=");
    con_dec_u32(p->energy);
    con_nl();
}

int main(void)
{
    int i, step;
    struct particle copy;
    struct big b1, b2;
    u32 h = 0;

    con_init();
    con_puts("structs: copy, pass, return, arrays, packed\n");

    con_kv_u32("sizeof packed record", (u32)sizeof(struct record));
    check(sizeof(struct record) == 10u, "packed size");

    /* .data initialisers arrived intact. */
    for (i = 0; i < 6; i++) {
        print_particle(&swarm[i]);
    }
    /* .bss is zero. */
    for (i = 0; i < 24; i++) {
        check(scratch.words[i] == 0u, "bss zero");
    }

    /* Copy, modify the copy, the original is unchanged. */
    copy = swarm[2];
    copy.pos.x = 999;
    copy.tag[1] = 'A';
    check(swarm[2].pos.x == 100 && swarm[2].tag[1] == 'a', "copy is independent");
    check(copy.energy == swarm[2].energy, "copy equal");

    for (step = 0; step < 20; step++) {
        for (i = 0; i < 6; i++) {
            swarm[i] = particle_step(swarm[i], step + i);
        }
    }
    for (i = 0; i < 6; i++) {
        h = fold(h, particle_hash(&swarm[i]));
    }
    con_kv_hex32("hash after steps", h);
    sort_by_energy(swarm, 6);
    for (i = 0; i < 6; i++) {
        print_particle(&swarm[i]);
    }
    for (i = 1; i < 6; i++) {
        check(swarm[i - 1].energy <= swarm[i].energy, "sorted");
    }

    /* Large structures by value, structure assignment via memcpy. */
    b1 = big_fill(7u);
    b2 = b1;
    scratch = b2;
    b2.words[23] ^= 1u;
    con_kv_hex32("big sum b1", big_sum(b1));
    con_kv_hex32("big sum b2", big_sum(b2));
    con_kv_hex32("big sum scratch", big_sum(scratch));
    check(big_sum(b1) == big_sum(scratch), "big copy");

    /* Packed records at odd offsets. */
    for (i = 0; i < 8; i++) {
        record_write(&log_buf[i], (u8)(i * 37), 0x01020304u * (u32)(i + 1), (i16)(-1000 * i + 7));
    }
    h = 0;
    for (i = 0; i < 8; i++) {
        h = fold(h, record_read(&log_buf[i]));
    }
    con_kv_hex32("packed stamp[3]", log_buf[3].stamp);
    con_kv_i32("packed value[7]", log_buf[7].value);
    con_kv_hex32("packed crc[5]", log_buf[5].crc);
    con_kv_hex32("hash packed", h);
    return finish();
}

/*
 * funcptr.c - function pointers: tables of callbacks, a comparator-driven
 * generic sort, a state machine whose states are functions, "objects" with
 * a table of operations, and functions returning function pointers.
 *
 * Indirect calls compile to JSR @ERn; tables of pointers live in .rodata
 * (ROM) or .data (RAM) as 32-bit addresses.
 */
#include "testlib.h"

typedef i32 (*binop_fn)(i32, i32);

static NOINLINE i32 op_add(i32 a, i32 b) { return (i32)((u32)a + (u32)b); }
static NOINLINE i32 op_sub(i32 a, i32 b) { return (i32)((u32)a - (u32)b); }
static NOINLINE i32 op_mul(i32 a, i32 b) { return (i32)((u32)a * (u32)b); }
static NOINLINE i32 op_and(i32 a, i32 b) { return a & b; }
static NOINLINE i32 op_xor(i32 a, i32 b) { return a ^ b; }
static NOINLINE i32 op_max(i32 a, i32 b) { return (a > b) ? a : b; }
static NOINLINE i32 op_min(i32 a, i32 b) { return (a < b) ? a : b; }
/* Floor of the mean without overflow (arithmetic shifts, as GCC does). */
static NOINLINE i32 op_avg(i32 a, i32 b) { return (a >> 1) + (b >> 1) + (a & b & 1); }

/* A constant table in ROM. */
static const binop_fn rom_ops[8] = {
    op_add, op_sub, op_mul, op_and, op_xor, op_max, op_min, op_avg,
};
static const char *const op_names[8] = { "add", "sub", "mul", "and", "xor", "max", "min", "avg" };

/* A writable table in RAM (initialised from ROM by crt0), rotated at run time. */
static binop_fn ram_ops[8] = {
    op_avg, op_min, op_max, op_xor, op_and, op_mul, op_sub, op_add,
};

static NOINLINE i32 fold_with(binop_fn f, const i32 *v, int n)
{
    i32 acc = v[0];
    int i;
    for (i = 1; i < n; i++) {
        acc = f(acc, v[i]);
    }
    return acc;
}

/* Generic insertion sort over an array of u32 with a comparator. */
typedef int (*cmp_fn)(u32, u32);

static NOINLINE int cmp_up(u32 a, u32 b) { return (a > b) - (a < b); }
static NOINLINE int cmp_down(u32 a, u32 b) { return (a < b) - (a > b); }
static NOINLINE int cmp_signed(u32 a, u32 b) { return ((i32)a > (i32)b) - ((i32)a < (i32)b); }
static NOINLINE int cmp_popcount(u32 a, u32 b)
{
    int pa = 0, pb = 0;
    while (a != 0u) {
        a &= a - 1u;
        pa++;
    }
    while (b != 0u) {
        b &= b - 1u;
        pb++;
    }
    return pa - pb;
}

static NOINLINE void sort_u32(u32 *a, int n, cmp_fn cmp)
{
    int i, j;
    for (i = 1; i < n; i++) {
        u32 key = a[i];
        for (j = i - 1; j >= 0 && cmp(a[j], key) > 0; j--) {
            a[j + 1] = a[j];
        }
        a[j + 1] = key;
    }
}

/* A state machine: each state is a function returning the index of the
 * next state in a table of state functions. */
struct machine {
    u32 count;
    u32 value;
    u32 trace;
};
enum { ST_IDLE, ST_NUMBER, ST_WORD, N_STATES };
typedef u8 (*state_fn)(struct machine *m, u8 input);

static NOINLINE u8 st_idle(struct machine *m, u8 in)
{
    m->trace = fold(m->trace, 1u);
    if (in >= '0' && in <= '9') {
        m->value = (u32)(in - '0');
        return ST_NUMBER;
    }
    if (in >= 'a' && in <= 'z') {
        return ST_WORD;
    }
    return ST_IDLE;
}

static NOINLINE u8 st_number(struct machine *m, u8 in)
{
    m->trace = fold(m->trace, 2u);
    if (in >= '0' && in <= '9') {
        m->value = m->value * 10u + (u32)(in - '0');
        return ST_NUMBER;
    }
    m->count += m->value;
    return st_idle(m, in);
}

static NOINLINE u8 st_word(struct machine *m, u8 in)
{
    m->trace = fold(m->trace, 3u);
    if (in >= 'a' && in <= 'z') {
        m->count++;
        return ST_WORD;
    }
    return st_idle(m, in);
}

static const state_fn states[N_STATES] = { st_idle, st_number, st_word };

/* Objects with an operations table ("vtable"). */
struct shape;
struct shape_ops {
    i32 (*area)(const struct shape *s);
    i32 (*perimeter)(const struct shape *s);
    const char *name;
};
struct shape {
    const struct shape_ops *ops;
    i32 a, b;
};

static NOINLINE i32 rect_area(const struct shape *s) { return s->a * s->b; }
static NOINLINE i32 rect_perimeter(const struct shape *s) { return 2 * (s->a + s->b); }
static NOINLINE i32 square_area(const struct shape *s) { return s->a * s->a; }
static NOINLINE i32 square_perimeter(const struct shape *s) { return 4 * s->a; }
static NOINLINE i32 tri_area(const struct shape *s) { return s->a * s->b / 2; }
static NOINLINE i32 tri_perimeter(const struct shape *s) { return s->a + s->b + (s->a > s->b ? s->a : s->b); }

static const struct shape_ops rect_ops = { rect_area, rect_perimeter, "rect" };
static const struct shape_ops square_ops = { square_area, square_perimeter, "square" };
static const struct shape_ops tri_ops = { tri_area, tri_perimeter, "tri" };

/* A function returning a function pointer. */
static NOINLINE binop_fn pick(u32 selector)
{
    return rom_ops[selector & 7u];
}

/* Callbacks with a context pointer. */
typedef void (*visit_fn)(void *ctx, u32 value);
static NOINLINE void for_each(const u32 *v, int n, visit_fn f, void *ctx)
{
    int i;
    for (i = 0; i < n; i++) {
        f(ctx, v[i]);
    }
}
static NOINLINE void visit_sum(void *ctx, u32 value) { *(u32 *)ctx += value; }
static NOINLINE void visit_hash(void *ctx, u32 value) { *(u32 *)ctx = fold(*(u32 *)ctx, value); }

int main(void)
{
    static const i32 values[6] = { 17, -4, 1000, 33, -250, 7 };
    static const char input[] = "abc 12 x 345 zz 6 q99 end";
    u32 arr[16];
    u32 h, i;
    int k;
    struct machine m = { 0u, 0u, 0u };
    struct shape shapes[3];
    u8 st = ST_IDLE;

    con_init();
    con_puts("funcptr: callback tables, comparators, state machine, vtables\n");

    for (k = 0; k < 8; k++) {
        con_puts(op_names[k]);
        con_putchar(' ');
        con_dec_i32(rom_ops[k](-37, 12));
        con_putchar(' ');
        con_dec_i32(fold_with(rom_ops[k], values, 6));
        con_nl();
    }
    /* Rotate the RAM table and use it. */
    h = 0;
    for (k = 0; k < 16; k++) {
        binop_fn first = ram_ops[0];
        int j;
        for (j = 0; j < 7; j++) {
            ram_ops[j] = ram_ops[j + 1];
        }
        ram_ops[7] = first;
        h = fold(h, (u32)ram_ops[k & 7](k * 1000 - 5000, 77 - k));
    }
    con_kv_hex32("ram table hash", h);
    check(ram_ops[0] == op_avg, "ram table rotated back");

    /* One array, four orders. */
    {
        static const cmp_fn cmps[4] = { cmp_up, cmp_down, cmp_signed, cmp_popcount };
        static const char *const cmp_names[4] = { "up", "down", "signed", "popcount" };
        int c;
        for (c = 0; c < 4; c++) {
            rng_seed(0xC0FFEE00u);
            for (i = 0; i < 16; i++) {
                arr[i] = rng_next() >> (i & 7u);
            }
            sort_u32(arr, 16, cmps[c]);
            h = 0;
            for (i = 0; i < 16; i++) {
                h = fold(h, arr[i]);
                if (i > 0u) {
                    check(cmps[c](arr[i - 1u], arr[i]) <= 0, "comparator order");
                }
            }
            con_puts("sort ");
            con_puts(cmp_names[c]);
            con_puts(" first=");
            con_hex32(arr[0]);
            con_puts(" last=");
            con_hex32(arr[15]);
            con_puts(" hash=");
            con_hex32(h);
            con_nl();
        }
    }

    /* State machine over a string, with a final separator. */
    for (i = 0; i < sizeof(input); i++) {
        u8 c = (u8)input[i];
        if (c == 0u) {
            c = ' ';
        }
        st = states[st](&m, c);
    }
    con_kv_u32("machine count", m.count);
    con_kv_hex32("machine trace", m.trace);

    shapes[0].ops = &rect_ops;
    shapes[0].a = 7;
    shapes[0].b = 9;
    shapes[1].ops = &square_ops;
    shapes[1].a = 12;
    shapes[1].b = 0;
    shapes[2].ops = &tri_ops;
    shapes[2].a = 10;
    shapes[2].b = 5;
    for (k = 0; k < 3; k++) {
        con_puts(shapes[k].ops->name);
        con_puts(" area=");
        con_dec_i32(shapes[k].ops->area(&shapes[k]));
        con_puts(" perimeter=");
        con_dec_i32(shapes[k].ops->perimeter(&shapes[k]));
        con_nl();
    }

    h = 0;
    for (i = 0; i < 64; i++) {
        u32 r = rng_next();
        h = fold(h, (u32)pick(r)((i32)(r >> 8), (i32)i - 32));
    }
    con_kv_hex32("pick hash", h);

    {
        u32 sum = 0, hh = 0;
        static const u32 items[5] = { 1u, 20u, 300u, 4000u, 50000u };
        for_each(items, 5, visit_sum, &sum);
        for_each(items, 5, visit_hash, &hh);
        con_kv_u32("for_each sum", sum);
        con_kv_hex32("for_each hash", hh);
    }
    return finish();
}

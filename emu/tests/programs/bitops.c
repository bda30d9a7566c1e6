/*
 * bitops.c - bitwise logic, bit-fields and the H8 bit-manipulation
 * instructions.
 *
 * C part: AND/OR/XOR/NOT at 8/16/32 bits (GCC uses byte, word and E-register
 * halves), bit-fields (signed and unsigned, read-modify-write through shifts
 * and masks; only values are compared, never the layout, which differs
 * between host and target), population count, parity, bit reversal, Gray
 * code, single-bit test (GCC emits BLD for it).
 *
 * Bit-instruction part: GCC 3.4 emits BSET/BCLR/BNOT on memory only for
 * non-volatile @aa:8 (I/O) operands, so the H8 bit instructions are reached
 * through inline assembly on the target - register and @ERd forms, bit
 * numbers as immediates and in a register (only its low 3 bits count) - and
 * computed in C on the host: BSET, BCLR, BNOT, BTST (Z read back with STC),
 * BLD, BILD, BST, BIST, BAND, BIAND, BOR, BIOR, BXOR, BIXOR.
 */
#include "testlib.h"

/* ---- plain C logic ---------------------------------------------------- */

static NOINLINE u32 logic8(u8 a, u8 b)
{
    u8 x = (u8)(a & b), y = (u8)(a | b), z = (u8)(a ^ b), n = (u8)~a;
    return (u32)x | (u32)y << 8 | (u32)z << 16 | (u32)n << 24;
}

static NOINLINE u32 logic16(u16 a, u16 b)
{
    u16 x = (u16)(a & b), y = (u16)(a | b), z = (u16)(a ^ b), n = (u16)~b;
    return ((u32)x << 16 | y) ^ ((u32)z << 8) ^ ((u32)n << 3);
}

static NOINLINE u32 logic32(u32 a, u32 b)
{
    return (a & b) ^ ((a | b) << 1) ^ ((a ^ b) >> 1) ^ ~(a & 0x0F0F0F0Fu);
}

/* Constant masks: GCC splits these into byte/word operations. */
static NOINLINE u32 masks32(u32 a)
{
    u32 h = 0;
    h = fold(h, a & 0xFFu);
    h = fold(h, a & 0xFF00u);
    h = fold(h, a & 0xFFFF0000u);
    h = fold(h, a | 0x80000000u);
    h = fold(h, a | 0x00010000u);
    h = fold(h, a ^ 0x0000FFFFu);
    h = fold(h, a ^ 0x80808080u);
    h = fold(h, a & ~0x00000100u);
    return h;
}

static NOINLINE int popcount32(u32 v)
{
    int n = 0;
    while (v != 0u) {
        v &= v - 1u;
        n++;
    }
    return n;
}

static NOINLINE int parity16(u16 v)
{
    v ^= (u16)(v >> 8);
    v ^= (u16)(v >> 4);
    v ^= (u16)(v >> 2);
    v ^= (u16)(v >> 1);
    return v & 1;
}

static NOINLINE u32 reverse32(u32 v)
{
    v = ((v >> 1) & 0x55555555u) | ((v & 0x55555555u) << 1);
    v = ((v >> 2) & 0x33333333u) | ((v & 0x33333333u) << 2);
    v = ((v >> 4) & 0x0F0F0F0Fu) | ((v & 0x0F0F0F0Fu) << 4);
    v = ((v >> 8) & 0x00FF00FFu) | ((v & 0x00FF00FFu) << 8);
    return (v >> 16) | (v << 16);
}

static NOINLINE u16 gray16(u16 v)
{
    return (u16)(v ^ (v >> 1));
}

static NOINLINE u16 ungray16(u16 g)
{
    u16 v = g;
    while ((g = (u16)(g >> 1)) != 0u) {
        v ^= g;
    }
    return v;
}

static NOINLINE int test_bit4(const u8 *p)
{
    return (*p & 0x10u) != 0u;
}

/* ---- bit-fields ------------------------------------------------------- */

struct fields {
    unsigned int flag : 1;
    unsigned int mode : 3;
    unsigned int level : 5;
    signed int delta : 6;
    unsigned int wide : 12;
    signed int tiny : 2;
};

static struct fields fld;

static NOINLINE void fields_step(u32 r)
{
    fld.flag = !fld.flag;
    fld.mode = (fld.mode + 3u) & 7u;
    fld.level = (fld.level + (r & 31u)) & 31u;
    /* Keep delta within -32..31 by wrapping in unsigned and sign-adjusting. */
    {
        i32 d = fld.delta + (i32)(r >> 5 & 7u) - 3;
        if (d > 31) {
            d -= 64;
        }
        if (d < -32) {
            d += 64;
        }
        fld.delta = d;
    }
    fld.wide = (fld.wide ^ (r >> 8)) & 0xFFFu;
    fld.tiny = (i32)((r >> 20) & 3u) - 2;
}

static u32 fields_value(void)
{
    return (u32)fld.flag | (u32)fld.mode << 1 | (u32)fld.level << 4 |
           ((u32)(fld.delta + 32) << 9) | ((u32)fld.wide << 15) | ((u32)(fld.tiny + 2) << 27);
}

/* ---- H8 bit instructions (target) and their C meaning (host) ----------- */

#ifdef __H8300H__
#define ASM_R_BITOP(name, insn)                                                \
    static NOINLINE u8 name(u8 v, u8 n)                                        \
    {                                                                          \
        __asm__(insn " %X2,%X0" : "=r"(v) : "0"(v), "r"(n));                   \
        return v;                                                              \
    }
#define ASM_M_BITOP(name, insn)                                                \
    static NOINLINE void name(u8 *p, u8 n)                                     \
    {                                                                          \
        __asm__ volatile(insn " %X1,@%0" : : "r"(p), "r"(n) : "memory");       \
    }
ASM_R_BITOP(bset_r, "bset")
ASM_R_BITOP(bclr_r, "bclr")
ASM_R_BITOP(bnot_r, "bnot")
ASM_M_BITOP(bset_m, "bset")
ASM_M_BITOP(bclr_m, "bclr")
ASM_M_BITOP(bnot_m, "bnot")

/* Immediate bit numbers on a register and on @ERd. */
static NOINLINE u8 imm_ops(u8 v)
{
    __asm__("bset #0,%X0\n\tbclr #7,%X0\n\tbnot #3,%X0\n\tbnot #5,%X0" : "+r"(v));
    return v;
}

static NOINLINE void imm_ops_m(u8 *p)
{
    __asm__ volatile("bset #6,@%0\n\tbclr #1,@%0\n\tbnot #4,@%0" : : "r"(p) : "memory");
}

/* BTST: Z = 1 when the bit is 0. STC copies CCR; keep only Z (bit 2). */
static NOINLINE u8 btst_z(u8 v, u8 n)
{
    u8 c;
    __asm__("btst %X2,%X1\n\tstc ccr,%X0" : "=&r"(c) : "r"(v), "r"(n));
    return (u8)(c & 0x04u);
}

static NOINLINE u8 btst_z_m(const u8 *p)
{
    u8 c;
    __asm__ volatile("btst #2,@%1\n\tstc ccr,%X0" : "=r"(c) : "r"(p) : "memory");
    return (u8)(c & 0x04u);
}

/* Carry-flag logic: each result bit is one BLD/BILD, one logic op, one
 * BST/BIST. */
static NOINLINE u8 carry_logic(u8 a, u8 b, const u8 *m)
{
    u8 r = 0;
    __asm__("bld #0,%X1\n\tband #1,%X2\n\tbst #0,%X0\n\t"
            "bld #2,%X1\n\tbor #3,%X2\n\tbst #1,%X0\n\t"
            "bild #4,%X1\n\tbxor #5,%X2\n\tbst #2,%X0\n\t"
            "bld #6,%X1\n\tbiand #7,%X2\n\tbst #3,%X0\n\t"
            "bld #1,%X2\n\tbior #0,%X2\n\tbist #4,%X0\n\t"
            "bld #7,%X1\n\tbixor #2,%X2\n\tbst #5,%X0\n\t"
            "bld #3,@%3\n\tband #5,@%3\n\tbst #6,%X0\n\t"
            "bild #0,@%3\n\tbxor #7,%X1\n\tbist #7,%X0"
            : "+r"(r)
            : "r"(a), "r"(b), "r"(m)
            : "memory");
    return r;
}

/* BST/BIST to memory. */
static NOINLINE void store_bits_m(u8 *p, u8 src)
{
    __asm__ volatile("bld #0,%X1\n\tbst #7,@%0\n\tbld #1,%X1\n\tbist #6,@%0" : : "r"(p), "r"(src) : "memory");
}

#else /* host: the same operations in C */

#define BIT(n) ((u8)(1u << ((n) & 7u)))
#define GETBIT(v, n) (((v) >> (n)) & 1u)
static NOINLINE u8 bset_r(u8 v, u8 n) { return (u8)(v | BIT(n)); }
static NOINLINE u8 bclr_r(u8 v, u8 n) { return (u8)(v & (u8)~BIT(n)); }
static NOINLINE u8 bnot_r(u8 v, u8 n) { return (u8)(v ^ BIT(n)); }
static NOINLINE void bset_m(u8 *p, u8 n) { *p = (u8)(*p | BIT(n)); }
static NOINLINE void bclr_m(u8 *p, u8 n) { *p = (u8)(*p & (u8)~BIT(n)); }
static NOINLINE void bnot_m(u8 *p, u8 n) { *p = (u8)(*p ^ BIT(n)); }

static NOINLINE u8 imm_ops(u8 v)
{
    v = (u8)(v | 0x01u);
    v = (u8)(v & 0x7Fu);
    v = (u8)(v ^ 0x08u);
    v = (u8)(v ^ 0x20u);
    return v;
}

static NOINLINE void imm_ops_m(u8 *p)
{
    *p = (u8)(((*p | 0x40u) & 0xFDu) ^ 0x10u);
}

static NOINLINE u8 btst_z(u8 v, u8 n) { return (v & BIT(n)) ? 0u : 0x04u; }
static NOINLINE u8 btst_z_m(const u8 *p) { return (*p & 0x04u) ? 0u : 0x04u; }

static NOINLINE u8 carry_logic(u8 a, u8 b, const u8 *m)
{
    u8 r = 0;
    u32 c;
    c = GETBIT(a, 0) & GETBIT(b, 1);
    r = (u8)(r | c << 0);
    c = GETBIT(a, 2) | GETBIT(b, 3);
    r = (u8)(r | c << 1);
    c = (GETBIT(a, 4) ^ 1u) ^ GETBIT(b, 5);
    r = (u8)(r | c << 2);
    c = GETBIT(a, 6) & (GETBIT(b, 7) ^ 1u);
    r = (u8)(r | c << 3);
    c = GETBIT(b, 1) | (GETBIT(b, 0) ^ 1u);
    r = (u8)(r | (c ^ 1u) << 4);
    c = GETBIT(a, 7) ^ (GETBIT(b, 2) ^ 1u);
    r = (u8)(r | c << 5);
    c = GETBIT(*m, 3) & GETBIT(*m, 5);
    r = (u8)(r | c << 6);
    c = (GETBIT(*m, 0) ^ 1u) ^ GETBIT(a, 7);
    r = (u8)(r | (c ^ 1u) << 7);
    return r;
}

static NOINLINE void store_bits_m(u8 *p, u8 src)
{
    u8 v = *p;
    v = (u8)((v & 0x7Fu) | (GETBIT(src, 0) << 7));
    v = (u8)((v & 0xBFu) | ((GETBIT(src, 1) ^ 1u) << 6));
    *p = v;
}
#endif

int main(void)
{
    u32 h_logic = 0, h_misc = 0, h_fields = 0, h_bitr = 0, h_bitm = 0, h_carry = 0;
    u32 i;
    u8 mem;

    con_init();
    con_puts("bitops: logic, bit-fields, H8 bit instructions\n");

    con_kv_hex32("logic8 0xF0,0x3C", logic8(0xF0, 0x3C));
    con_kv_hex32("logic16 0x1234,0xFF00", logic16(0x1234u, 0xFF00u));
    con_kv_hex32("logic32 0xDEADBEEF,0x01234567", logic32(0xDEADBEEFu, 0x01234567u));
    con_kv_i32("popcount 0xF00FF00F", popcount32(0xF00FF00Fu));
    con_kv_i32("parity 0x7001", parity16(0x7001u));
    con_kv_hex32("reverse 0x00000001", reverse32(1u));
    con_kv_hex32("reverse 0x12345678", reverse32(0x12345678u));
    con_kv_hex32("gray 1000", gray16(1000u));
    con_kv_hex32("bset r 0x00,#(11&7)", bset_r(0x00, 11));
    con_kv_hex32("bclr r 0xFF,7", bclr_r(0xFF, 7));
    con_kv_hex32("bnot r 0x55,0", bnot_r(0x55, 0));
    con_kv_hex32("imm_ops 0x80", imm_ops(0x80));
    con_kv_hex32("btst z 0x08,3", btst_z(0x08, 3));
    con_kv_hex32("btst z 0x08,4", btst_z(0x08, 4));
    con_kv_hex32("carry_logic 0xA5,0x3C", carry_logic(0xA5, 0x3C, (const u8 *)"\x29"));

    check(reverse32(reverse32(0xCAFEBABEu)) == 0xCAFEBABEu, "reverse twice");
    check(popcount32(0xFFFFFFFFu) == 32, "popcount all");
    mem = 0x10;
    check(test_bit4(&mem) == 1, "bld bit 4 set");
    mem = 0xEF;
    check(test_bit4(&mem) == 0, "bld bit 4 clear");

    rng_seed(0xB17B17B1u);
    for (i = 0; i < 256; i++) {
        u32 r = rng_next();
        u8 v = (u8)i;
        u8 n = (u8)(r & 15u); /* 8..15 check that only the low 3 bits count */
        h_logic = fold(h_logic, logic8(v, (u8)r));
        h_logic = fold(h_logic, logic16((u16)(r >> 8), (u16)(i * 257u)));
        h_logic = fold(h_logic, logic32(r, i * 0x01010101u));
        h_logic = fold(h_logic, masks32(r ^ i));
        h_misc = fold(h_misc, (u32)popcount32(r) | (u32)parity16((u16)r) << 8);
        h_misc = fold(h_misc, reverse32(r));
        h_misc = fold(h_misc, gray16((u16)r));
        check(ungray16(gray16((u16)r)) == (u16)r, "gray round trip");
        fields_step(r);
        h_fields = fold(h_fields, fields_value());
        h_bitr = fold(h_bitr, bset_r(v, n) | (u32)bclr_r(v, n) << 8 | (u32)bnot_r(v, n) << 16 |
                                  (u32)imm_ops(v) << 24);
        h_bitr = fold(h_bitr, btst_z(v, n));
        mem = v;
        bset_m(&mem, n);
        h_bitm = fold(h_bitm, mem);
        bnot_m(&mem, (u8)(n + 3u));
        h_bitm = fold(h_bitm, mem);
        bclr_m(&mem, (u8)(r >> 4));
        h_bitm = fold(h_bitm, mem);
        imm_ops_m(&mem);
        h_bitm = fold(h_bitm, mem);
        h_bitm = fold(h_bitm, btst_z_m(&mem));
        store_bits_m(&mem, (u8)(r >> 9));
        h_bitm = fold(h_bitm, mem);
        mem = (u8)(r >> 16);
        h_carry = fold(h_carry, carry_logic(v, (u8)(r >> 24), &mem));
    }
    con_puts("fields flag=");
    con_dec_u32(fld.flag);
    con_puts(" mode=");
    con_dec_u32(fld.mode);
    con_puts(" level=");
    con_dec_u32(fld.level);
    con_puts(" delta=");
    con_dec_i32(fld.delta);
    con_puts(" wide=");
    con_dec_u32(fld.wide);
    con_puts(" tiny=");
    con_dec_i32(fld.tiny);
    con_nl();

    con_kv_hex32("hash logic", h_logic);
    con_kv_hex32("hash misc", h_misc);
    con_kv_hex32("hash fields", h_fields);
    con_kv_hex32("hash bit reg", h_bitr);
    con_kv_hex32("hash bit mem", h_bitm);
    con_kv_hex32("hash carry", h_carry);
    return finish();
}

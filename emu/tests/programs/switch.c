/*
 * switch.c - switch statements: a dense switch (GCC emits a jump table: an
 * indexed load of a 32-bit address and JMP @ERn), a sparse switch (a tree of
 * compares and branches), a switch on a signed byte with negative cases and
 * fall-through, and a small bytecode interpreter built on a dense switch.
 */
#include "testlib.h"

/* Dense: 0..15 all handled, default for the rest. */
static NOINLINE u32 dense(u32 k, u32 x)
{
    switch (k) {
    case 0: return x + 1u;
    case 1: return x ^ 0xFFu;
    case 2: return x << 3;
    case 3: return x >> 2;
    case 4: return x * 3u;
    case 5: return x - 100u;
    case 6: return ~x;
    case 7: return x & 0xF0F0u;
    case 8: return x | 0x8000u;
    case 9: return (x << 16) | (x >> 16);
    case 10: return x + x;
    case 11: return 0u - x;
    case 12: return x ^ (x >> 7);
    case 13: return 12345u;
    case 14: return x & 1u;
    case 15: return x / 7u;
    default: return 0xDEADu;
    }
}

/* Sparse: values far apart, including large and 32-bit ones. */
static NOINLINE int sparse(i32 k)
{
    switch (k) {
    case -1000000: return 1;
    case -7: return 2;
    case 0: return 3;
    case 3: return 4;
    case 100: return 5;
    case 1000: return 6;
    case 4096: return 7;
    case 65535: return 8;
    case 65536: return 9;
    case 1000000: return 10;
    case I32_MAX: return 11;
    case I32_MIN: return 12;
    default: return 0;
    }
}

/* On a signed byte, with fall-through. */
static NOINLINE u32 byte_switch(i8 c)
{
    u32 r = 0;
    switch (c) {
    case -128:
        r += 1u;
        /* fall through */
    case -1:
        r += 10u;
        /* fall through */
    case 0:
        r += 100u;
        break;
    case 1:
    case 2:
    case 3:
        r += 1000u;
        break;
    case 'A':
        r = 65u;
        break;
    case 127:
        r = 0x7Fu;
        /* fall through */
    default:
        r += 7u;
        break;
    }
    return r;
}

/* A stack-machine bytecode interpreter. */
enum {
    VM_HALT, VM_PUSH, VM_ADD, VM_SUB, VM_MUL, VM_DUP, VM_SWAP, VM_DROP,
    VM_JNZ, VM_DEC, VM_OUT, VM_OVER, VM_NEG, VM_SHL, VM_SHR, VM_LT,
    VM_ROT,
};

#define VM_STACK 16
/* The stack starts at this index, so a buggy program that underflows by an
 * element or two stays inside the array until the check after the op. */
#define VM_BASE 2

static NOINLINE u32 vm_run(const u8 *code, u32 *steps)
{
    i32 stack[VM_STACK];
    int sp = VM_BASE;
    u32 pc = 0;
    u32 out = 0;
    u32 n = 0;
    for (;;) {
        u8 op = code[pc++];
        n++;
        if (n > 100000u) {
            break;
        }
        switch (op) {
        case VM_HALT:
            *steps = n;
            return out;
        case VM_PUSH:
            stack[sp++] = (i8)code[pc++];
            break;
        case VM_ADD:
            sp--;
            stack[sp - 1] = (i32)((u32)stack[sp - 1] + (u32)stack[sp]);
            break;
        case VM_SUB:
            sp--;
            stack[sp - 1] = (i32)((u32)stack[sp - 1] - (u32)stack[sp]);
            break;
        case VM_MUL:
            sp--;
            stack[sp - 1] = (i32)((u32)stack[sp - 1] * (u32)stack[sp]);
            break;
        case VM_DUP:
            stack[sp] = stack[sp - 1];
            sp++;
            break;
        case VM_SWAP: {
            i32 t = stack[sp - 1];
            stack[sp - 1] = stack[sp - 2];
            stack[sp - 2] = t;
            break;
        }
        case VM_DROP:
            sp--;
            break;
        case VM_JNZ: {
            i8 off = (i8)code[pc++];
            if (stack[--sp] != 0) {
                pc = (u32)((i32)pc + off);
            }
            break;
        }
        case VM_DEC:
            stack[sp - 1] = (i32)((u32)stack[sp - 1] - 1u);
            break;
        case VM_OUT:
            out = fold(out, (u32)stack[sp - 1]);
            con_dec_i32(stack[sp - 1]);
            con_putchar(' ');
            break;
        case VM_OVER:
            stack[sp] = stack[sp - 2];
            sp++;
            break;
        case VM_NEG:
            stack[sp - 1] = (i32)(0u - (u32)stack[sp - 1]);
            break;
        case VM_SHL:
            stack[sp - 1] = (i32)((u32)stack[sp - 1] << 1);
            break;
        case VM_SHR:
            stack[sp - 1] >>= 1;
            break;
        case VM_LT:
            sp--;
            stack[sp - 1] = stack[sp - 1] < stack[sp];
            break;
        case VM_ROT: {
            i32 t = stack[sp - 3];
            stack[sp - 3] = stack[sp - 2];
            stack[sp - 2] = stack[sp - 1];
            stack[sp - 1] = t;
            break;
        }
        default:
            *steps = n;
            return 0xBADu;
        }
        if (sp < VM_BASE || sp > VM_STACK - 2) {
            *steps = n;
            return 0xBAD5u;
        }
    }
    *steps = n;
    return out;
}

/* Program 1: print the first 12 Fibonacci numbers. Stack: n a b. */
static const u8 prog_fib[] = {
    VM_PUSH, 12, VM_PUSH, 0, VM_PUSH, 1,    /* 0: n a b */
    VM_OVER, VM_OUT, VM_DROP,               /* 6: print a */
    VM_SWAP, VM_OVER, VM_ADD,               /* 9: n b a+b */
    VM_ROT, VM_DEC, VM_DUP,                 /* 12: b a+b n-1 n-1 */
    VM_JNZ, 1,                              /* 15: to 18 while n-1 != 0 */
    VM_HALT,                                /* 17 */
    VM_ROT, VM_ROT,                         /* 18: n-1 b a+b */
    VM_PUSH, 1, VM_JNZ, (u8)(i8)-18,        /* 20: back to 6 */
};

/* Program 2: 10! by a loop, then a few unary and compare operations. */
static const u8 prog_loop[] = {
    VM_PUSH, 1, VM_PUSH, 10,                /* 0: x i */
    VM_DUP, VM_OUT, VM_DROP,                /* 4: print i */
    VM_SWAP, VM_OVER, VM_MUL,               /* 7: i x*i */
    VM_SWAP, VM_DEC, VM_DUP,                /* 10: x*i i-1 i-1 */
    VM_JNZ, (u8)(i8)-11,                    /* 13: back to 4 */
    VM_DROP, VM_OUT,                        /* 15: print 10! */
    VM_NEG, VM_OUT, VM_SHR, VM_OUT, VM_SHL, VM_SHL, VM_OUT,
    VM_PUSH, 5, VM_PUSH, 9, VM_LT, VM_OUT,
    VM_PUSH, 9, VM_PUSH, 5, VM_LT, VM_OUT, VM_SUB, VM_OUT,
    VM_HALT,
};

static const u8 prog_bad[] = { VM_PUSH, 1, 0xEE };

int main(void)
{
    u32 h_dense = 0, h_sparse = 0, h_byte = 0, i, k, steps;
    static const i32 probes[] = {
        -1000000, -1000001, -7, -6, 0, 1, 3, 100, 999, 1000, 4096, 4097,
        65535, 65536, 65537, 1000000, I32_MAX, I32_MIN, I32_MAX - 1, -2,
    };

    con_init();
    con_puts("switch: dense jump table, sparse compare tree, byte switch, bytecode VM\n");

    for (k = 0; k < 18; k++) {
        con_puts("dense(");
        con_dec_u32(k);
        con_puts(")=");
        con_hex32(dense(k, 0x1234u));
        con_nl();
    }
    for (i = 0; i < sizeof(probes) / sizeof(probes[0]); i++) {
        con_puts("sparse(");
        con_dec_i32(probes[i]);
        con_puts(")=");
        con_dec_i32(sparse(probes[i]));
        con_nl();
    }
    for (i = 0; i < 256; i++) {
        h_byte = fold(h_byte, byte_switch((i8)(u8)i));
    }
    con_kv_u32("byte(-128)", byte_switch(-128));
    con_kv_u32("byte(-1)", byte_switch(-1));
    con_kv_u32("byte(2)", byte_switch(2));
    con_kv_u32("byte(127)", byte_switch(127));
    con_kv_u32("byte(50)", byte_switch(50));

    rng_seed(0x5171C4u);
    for (i = 0; i < 300; i++) {
        u32 r = rng_next();
        h_dense = fold(h_dense, dense(r & 31u, r >> 5));
        h_sparse = fold(h_sparse, (u32)sparse((i32)(r & 0x1FFFu) - 8));
        h_sparse = fold(h_sparse, (u32)sparse(probes[r % 20u]));
    }
    con_kv_hex32("hash dense", h_dense);
    con_kv_hex32("hash sparse", h_sparse);
    con_kv_hex32("hash byte", h_byte);

    con_puts("vm fib: ");
    con_kv_hex32("out", vm_run(prog_fib, &steps));
    con_kv_u32("vm fib steps", steps);
    con_puts("vm loop: ");
    con_kv_hex32("out", vm_run(prog_loop, &steps));
    con_kv_u32("vm loop steps", steps);
    con_kv_hex32("vm bad", vm_run(prog_bad, &steps));
    check(vm_run(prog_bad, &steps) == 0xBADu, "vm bad opcode");
    return finish();
}

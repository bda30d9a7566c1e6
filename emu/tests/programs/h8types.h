/*
 * h8types.h - fixed-width integer types shared by the H8/300H target build
 * (h8300-hms-gcc -mh -mint32) and the host build (gcc on an LP64 or ILP32 host).
 *
 * With -mint32, `int` is 32 bits on the target, as it is on every host we build
 * on, and `long` is 32 bits on the target but 64 bits on an LP64 host. So the
 * 32-bit types are spelled with `int`, never with `long`. The checks below
 * stop the build if any width differs, so host and target compute the same.
 */
#ifndef H8TYPES_H
#define H8TYPES_H

typedef signed char i8;
typedef unsigned char u8;
typedef short i16;
typedef unsigned short u16;
typedef int i32;
typedef unsigned int u32;
/* Sizes of objects (the target's size_t is a 32-bit unsigned int). */
typedef unsigned int usize;

#define I8_MIN (-128)
#define I8_MAX 127
#define U8_MAX 255u
#define I16_MIN (-32767 - 1)
#define I16_MAX 32767
#define U16_MAX 65535u
#define I32_MIN (-2147483647 - 1)
#define I32_MAX 2147483647
#define U32_MAX 4294967295u

/* Compile-time width checks: a negative array size is a compile error. */
typedef char h8types_check_i8[(sizeof(i8) == 1) ? 1 : -1];
typedef char h8types_check_i16[(sizeof(i16) == 2) ? 1 : -1];
typedef char h8types_check_i32[(sizeof(i32) == 4) ? 1 : -1];
typedef char h8types_check_int[(sizeof(int) == 4) ? 1 : -1];

#endif

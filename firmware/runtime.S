; runtime.S - the helpers that h8300-hms-gcc -mh -mint32 code calls, written
; for the H8/300H (Debian's libgcc for h8300-hms holds the plain-H8/300
; versions only, which do not fit -mh code).
;
; Calling convention of GCC 3.4 for the H8/300H (gcc/config/h8300/h8300.h:
; CALL_USED_REGISTERS, FUNCTION_VALUE; the GCC "H8/300 ABI" page; confirmed
; by compiling calls with this compiler):
;   - arguments: first in ER0, second in ER1, third in ER2, the rest on the
;     stack (pushed last to first, each rounded to 4 bytes); libcalls such as
;     __mulsi3 take their two operands in ER0 and ER1;
;   - result: ER0 (R0 for 16-bit, R0L for 8-bit values);
;   - ER0-ER3 are call-clobbered; ER4, ER5, ER6 are callee-saved (ER6 is the
;     frame pointer); ER7 is the stack pointer; the return address is a
;     4-byte push by JSR/BSR (advanced mode).
; Every helper below clobbers only ER0-ER3 (and CCR) or saves what it uses.
;
;   __mulsi3   ER0 = ER0 * ER1 (low 32 bits; same for signed and unsigned)
;   __udivsi3  ER0 = ER0 / ER1 (unsigned)
;   __umodsi3  ER0 = ER0 % ER1 (unsigned)
;   __divsi3   ER0 = ER0 / ER1 (signed, truncating toward zero, as C99)
;   __modsi3   ER0 = ER0 % ER1 (signed, sign of the dividend, as C99)
;   memcpy, memset: GCC emits calls to them for structure copies and
;     initialisers, even with -nostdlib.
; Division by zero is undefined in C and never done by the programs;
; here it returns whatever DIVXU leaves and never traps or loops.

	.h8300h
	.section .text

; ---------------------------------------------------------------------------
; __mulsi3: (a_hi:a_lo) * (b_hi:b_lo) mod 2^32
;   = a_lo*b_lo + ((a_lo*b_hi + a_hi*b_lo) mod 2^16) << 16
; MULXU.W Rs,ERd multiplies the low word of ERd by Rs into all of ERd.
	.align	1
	.global	___mulsi3
___mulsi3:
	mov.l	er0, er2
	mulxu.w	e1, er2			; ER2 = a_lo * b_hi
	mov.w	e0, r3
	mulxu.w	r1, er3			; ER3 = a_hi * b_lo
	add.w	r3, r2			; R2 = low word of the cross terms
	mulxu.w	r1, er0			; ER0 = a_lo * b_lo
	add.w	r2, e0			; add the cross terms into the high word
	rts

; ---------------------------------------------------------------------------
; udivmod32: ER0 = n, ER1 = d  ->  ER0 = n / d, ER1 = n % d (unsigned).
; Clobbers ER2, ER3.
;   d < 2^16: two DIVXU.W steps (32/16 -> 16-bit quotient and remainder);
;     dividing the high word first keeps each partial quotient in 16 bits.
;   d >= 2^16: the quotient fits in 16 bits; 16 steps of restoring
;     shift-and-subtract over the low word, starting from rem = n_hi (< d).
	.align	1
udivmod32:
	mov.w	e1, r2
	bne	.Lbig_divisor
	mov.w	e0, r2
	extu.l	er2			; ER2 = 0 : n_hi
	divxu.w	r1, er2			; R2 = q_hi, E2 = n_hi % d
	mov.w	r2, r3			; keep q_hi
	mov.w	r0, r2			; ER2 = (n_hi % d) : n_lo
	divxu.w	r1, er2			; R2 = q_lo, E2 = remainder
	mov.w	r3, e0
	mov.w	r2, r0			; ER0 = q_hi : q_lo
	mov.w	e2, r1
	extu.l	er1			; ER1 = remainder
	rts
.Lbig_divisor:
	mov.w	e0, r3
	extu.l	er3			; ER3 = partial remainder = n_hi
	mov.w	r0, e0
	sub.w	r0, r0			; ER0 = n_lo : 0
	mov.b	#16, r2l
.Lstep:
	shll.l	er0			; C = next dividend bit; bit 0 = 0
	rotxl.l	er3			; rem = rem << 1 | C; C = bit 32 of rem
	bcs	.Lsubtract		; rem >= 2^32 > d
	cmp.l	er1, er3
	bcs	.Lnext			; rem < d: quotient bit stays 0
.Lsubtract:
	sub.l	er1, er3		; (mod 2^32 also right after a carry out)
	adds	#1, er0			; quotient bit = 1
.Lnext:
	dec.b	r2l
	bne	.Lstep
	mov.l	er3, er1		; ER0 = quotient (high word now 0)
	rts

; ---------------------------------------------------------------------------
	.align	1
	.global	___udivsi3
___udivsi3:
	bsr	udivmod32
	rts

	.align	1
	.global	___umodsi3
___umodsi3:
	bsr	udivmod32
	mov.l	er1, er0
	rts

; ---------------------------------------------------------------------------
; Signed division on magnitudes. R4L holds the sign of the result
; (0x00 positive, 0xFF negative); ER4 is callee-saved, so it is pushed.
; The magnitude of I32_MIN is 0x80000000, right as an unsigned number.
	.align	1
	.global	___divsi3
___divsi3:
	mov.l	er4, @-er7
	sub.b	r4l, r4l
	mov.l	er0, er0
	bpl	.Ldiv_n_pos
	neg.l	er0
	not.b	r4l
.Ldiv_n_pos:
	mov.l	er1, er1
	bpl	.Ldiv_d_pos
	neg.l	er1
	not.b	r4l
.Ldiv_d_pos:
	bsr	udivmod32
	mov.b	r4l, r4l
	beq	.Ldiv_done
	neg.l	er0
.Ldiv_done:
	mov.l	@er7+, er4
	rts

	.align	1
	.global	___modsi3
___modsi3:
	mov.l	er4, @-er7
	sub.b	r4l, r4l
	mov.l	er0, er0
	bpl	.Lmod_n_pos
	neg.l	er0
	not.b	r4l			; the remainder takes the dividend's sign
.Lmod_n_pos:
	mov.l	er1, er1
	bpl	.Lmod_d_pos
	neg.l	er1
.Lmod_d_pos:
	bsr	udivmod32
	mov.l	er1, er0
	mov.b	r4l, r4l
	beq	.Lmod_done
	neg.l	er0
.Lmod_done:
	mov.l	@er7+, er4
	rts

; ---------------------------------------------------------------------------
; void *memcpy(void *dst /* ER0 */, const void *src /* ER1 */, size_t n /* ER2 */)
; Uses EEPMOV.W (copies R4 bytes from @ER5+ to @ER6+, counting R4 down to 0).
; ER4-ER6 are callee-saved, so they are pushed. Returns dst in ER0.
	.align	1
	.global	_memcpy
_memcpy:
	mov.l	er4, @-er7
	mov.l	er5, @-er7
	mov.l	er6, @-er7
	mov.l	er1, er5		; source
	mov.l	er0, er6		; destination
	mov.w	r2, r4			; n mod 2^16 bytes first
	beq	.Lcpy_blocks
	eepmov.w
.Lcpy_blocks:
	mov.w	e2, r3			; then n / 2^16 blocks of 64 KiB
	beq	.Lcpy_done
.Lcpy_block:
	mov.w	#0x8000, r4
	eepmov.w
	mov.w	#0x8000, r4
	eepmov.w
	dec.w	#1, r3
	bne	.Lcpy_block
.Lcpy_done:
	mov.l	@er7+, er6
	mov.l	@er7+, er5
	mov.l	@er7+, er4
	rts

; void *memset(void *dst /* ER0 */, int c /* ER1 */, size_t n /* ER2 */)
	.align	1
	.global	_memset
_memset:
	mov.l	er0, er3
	mov.l	er2, er2
	beq	.Lset_done
.Lset_byte:
	mov.b	r1l, @er3
	adds	#1, er3
	dec.l	#1, er2
	bne	.Lset_byte
.Lset_done:
	rts

; chip/crt0.S - start-up code for the chip test programs (emu/tests/programs/chip): the
; differential programs' crt0.S (../crt0.S, whose comments say the rest) with three vectors
; of the table pointing at handlers the program defines in C
; (__attribute__((interrupt_handler)): the handler saves what it uses and returns with RTE):
;   vector 12 (IRQ0)        _isr_irq0
;   vector 20 (WOVI, WDT)   _isr_wovi
;   vector 24 (IMIA0, ITU0) _isr_imia0
; Every other vector points at its stub (exit status 0x80 + vector number), as in ../crt0.S.
; A program that does not use one of the three defines it as a stub (chip.h's UNUSED_ISR).

	.h8300h

; The table is the start of crt0's .text: this old COFF toolchain cannot
; link objects with extra named sections, so the linker script places
; crt0.o's .text first, at H'000000, instead of using a .vectors section.
	.section .text
	.global __vectors
__vectors:
	.long	_start				; vector 0: reset
	.set	vn, 1
	.rept	11
	.long	__vector_stubs + 6 * (vn - 1)	; vectors 1..11
	.set	vn, vn + 1
	.endr
	.long	_isr_irq0			; vector 12: IRQ0
	.set	vn, 13
	.rept	7
	.long	__vector_stubs + 6 * (vn - 1)	; vectors 13..19
	.set	vn, vn + 1
	.endr
	.long	_isr_wovi			; vector 20: WOVI
	.set	vn, 21
	.rept	3
	.long	__vector_stubs + 6 * (vn - 1)	; vectors 21..23
	.set	vn, vn + 1
	.endr
	.long	_isr_imia0			; vector 24: IMIA0
	.set	vn, 25
	.rept	36
	.long	__vector_stubs + 6 * (vn - 1)	; vectors 25..60
	.set	vn, vn + 1
	.endr

; _start follows the table directly, at H'0000F4 (the linker script checks).
	.global	_start
_start:
	mov.l	#__stack_top, er7

	; Copy .data (run address in RAM) from its load image in ROM.
	mov.l	#__data_load, er0
	mov.l	#__data_start, er1
	mov.l	#__data_end, er2
.Lcopy_test:
	cmp.l	er2, er1
	bcc	.Lcopy_done			; er1 >= er2 (unsigned): done
	mov.b	@er0+, r3l
	mov.b	r3l, @er1
	adds	#1, er1
	bra	.Lcopy_test
.Lcopy_done:

	; Clear .bss.
	mov.l	#__bss_start, er1
	mov.l	#__bss_end, er2
	sub.b	r3l, r3l
.Lclear_test:
	cmp.l	er2, er1
	bcc	.Lclear_done
	mov.b	r3l, @er1
	adds	#1, er1
	bra	.Lclear_test
.Lclear_done:

	jsr	@_main
	; Fall through: exit status = R0L (main's return value, low byte).

	.global	__exit
__exit:
	orc	#0x80, ccr			; CCR.I = 1: mask interrupts
.Lsleep:
	sleep					; with I = 1: the emulator ends the run
	bra	.Lsleep				; should anything wake us, sleep again

; One stub per vector 1..60: exit status 0x80 + vector number.
	.align	1
__vector_stubs:
	.set	vn, 1
	.rept	60
	mov.b	#(0x80 + vn), r0l
	bra	__exit:16
	.set	vn, vn + 1
	.endr

; crt0.S - start-up code of the robot firmware on the H8/3052F (H8/300H, advanced mode).
;
;   H'000000  the exception vector table, 61 vectors of 4 bytes (docs/design.md §4.1): reset -> _start,
;             ITU0 IMIA (vector 24) -> _tick_isr, every other vector n -> a stub that ends
;             the run with exit status 0x80 + n (an unexpected exception is a fault);
;   H'0000F4  _start: stack at the top of RAM, .data copied, .bss cleared, main;
;   H'000400  the configuration block (docs/design.md §8), 32 bytes, erased (H'FF) in the image: the
;             emulator writes it at load; absent or corrupt, the firmware runs its defaults.
;
; The reset exception leaves CCR.I = 1; main enables interrupts when boot is done.

	.h8300h

; The table is the start of crt0's .text (the COFF linker script puts crt0.o first).
	.section .text
	.global __vectors
__vectors:
	.long	_start				; 0: reset
	.set	vn, 1
	.rept	23
	.long	__vector_stubs + 6 * (vn - 1)	; 1..23
	.set	vn, vn + 1
	.endr
	.long	_tick_isr			; 24: ITU0 IMIA0, the 10 ms tick
	.set	vn, 25
	.rept	36
	.long	__vector_stubs + 6 * (vn - 1)	; 25..60
	.set	vn, vn + 1
	.endr

	.global	_start
_start:
	mov.l	#__stack_top, er7
	; Copy .data from its load image in ROM.
	mov.l	#__data_load, er0
	mov.l	#__data_start, er1
	mov.l	#__data_end, er2
.Lcopy_test:
	cmp.l	er2, er1
	bcc	.Lcopy_done
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
	; main never returns; if it did, R0L is the exit status.

; __exit: the halt (docs/design.md §7). Also the return address the emulator gives a routine it calls
; by its symbol (h8swarm learn --on-core): the run stops here.
	.global	__exit
__exit:
	orc	#0x80, ccr
.Lsleep:
	sleep
	bra	.Lsleep

; One stub per vector 1..60: exit status 0x80 + vector number.
	.align	1
__vector_stubs:
	.set	vn, 1
	.rept	60
	mov.b	#(0x80 + vn), r0l
	bra	__exit:16
	.set	vn, vn + 1
	.endr

; The configuration block at H'000400 (see config.h), erased.
	.org	0x400
	.global	_config_block
_config_block:
	.rept	32
	.byte	0xff
	.endr

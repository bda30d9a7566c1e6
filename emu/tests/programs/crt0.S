; crt0.S - start-up code for the differential test programs on the emulated
; H8/3052F (H8/300H, advanced mode, 24-bit addresses).
;
; Layout and conventions (docs/design.md §4.1 and 7):
;   - The exception vector table sits at H'000000: 61 vectors of 4 bytes
;     (H'000000-H'0000F3). Vector 0 (reset) holds _start. Every other vector
;     points at its own 6-byte stub that loads 0x80 + vector number into R0L
;     and halts, so an unexpected interrupt or trap ends the run with a
;     nonzero exit status that names the vector (vector 1 -> 0x81 ... 60 -> 0xBC).
;   - _start sets ER7 to the top of on-chip RAM (H'FFFF10; RAM is
;     H'FFDF10-H'FFFF0F, the first push lands at H'FFFF0C), copies .data from
;     its load image in ROM to RAM, clears .bss and calls main.
;   - Halting: main's return value is in ER0; its low byte R0L is the exit
;     status. We set CCR.I with ORC and execute SLEEP; SLEEP with the interrupt
;     mask set (and no NMI) ends the run in the emulator. On a real chip SLEEP
;     would wait for NMI; if anything ever wakes us we loop back to SLEEP.
;
; The reset exception itself leaves CCR.I = 1 (hardware manual, "Reset"), so
; no interrupt can be taken before main; nothing here clears the mask.

	.h8300h

; The table is the start of crt0's .text: this old COFF toolchain cannot
; link objects with extra named sections, so the linker script places
; crt0.o's .text first, at H'000000, instead of using a .vectors section.
	.section .text
	.global __vectors
__vectors:
	.long	_start				; vector 0: reset
	.set	vn, 1
	.rept	60
	.long	__vector_stubs + 6 * (vn - 1)	; vectors 1..60
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

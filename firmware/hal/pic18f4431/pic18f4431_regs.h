/* Stand-in for <xc.h> with only the PIC18F4431 special-function registers and bits the
 * hardware layer uses, so that gcc can syntax-check hal_pic18f4431.c (make test) without the
 * XC8 compiler. Names and widths follow the PIC18F2331/2431/4331/4431 data sheet (DS39616);
 * addresses are not modelled. The real build includes <xc.h> instead. */
#ifndef PIC18F4431_REGS_H
#define PIC18F4431_REGS_H
#include <stdint.h>

#define __interrupt(x)
#define high_priority
#define low_priority
#define CLRWDT() ((void)0)
#define ei() ((void)0)
#define di() ((void)0)

extern volatile uint8_t OSCCON, INTCON, INTCON2, PIE1, PIR1, PIE3, PIR3, IPR1, RCON;
extern volatile uint8_t TRISA, TRISB, TRISC, TRISD, TRISE, ANSEL0, ANSEL1, LATD;
/* Timer1: 1 us tick (Fosc 32 MHz, Fcy 8 MHz, prescale 1:8) */
extern volatile uint8_t T1CON, TMR1H, TMR1L;
/* Timer5: window / scheduled-conversion compare (special event trigger to the ADC) */
extern volatile uint8_t T5CON, TMR5H, TMR5L, PR5H, PR5L;
/* power-control PWM module */
extern volatile uint8_t PTCON0, PTCON1, PTPERL, PTPERH, PDC0L, PDC0H, PDC1L, PDC1H, PDC2L,
    PDC2H, PWMCON0, PWMCON1, OVDCOND, OVDCONS, SEVTCMPL, SEVTCMPH, DTCON, FLTCONFIG;
/* high-speed ADC */
extern volatile uint8_t ADCON0, ADCON1, ADCON2, ADCON3, ADCHS, ADRESH, ADRESL;
/* EUSART */
extern volatile uint8_t TXSTA, RCSTA, BAUDCON, SPBRG, SPBRGH, TXREG, RCREG;

typedef struct {
    unsigned TMR1IF : 1;
    unsigned TMR2IF : 1;
    unsigned CCP1IF : 1;
    unsigned SSPIF : 1;
    unsigned TXIF : 1;
    unsigned RCIF : 1;
    unsigned ADIF : 1;
    unsigned : 1;
} PIR1bits_t;
extern volatile PIR1bits_t PIR1bits;

typedef struct {
    unsigned TMR5IF : 1;
    unsigned IC1IF : 1;
    unsigned IC2QEIF : 1;
    unsigned IC3DRIF : 1;
    unsigned PTIF : 1;
    unsigned : 3;
} PIR3bits_t;
extern volatile PIR3bits_t PIR3bits;

typedef struct {
    unsigned ADON : 1;
    unsigned GO_DONE : 1;
    unsigned ACMOD : 2;
    unsigned ACSCH : 1;
    unsigned ACONV : 1;
    unsigned : 2;
} ADCON0bits_t;
extern volatile ADCON0bits_t ADCON0bits;

typedef struct {
    unsigned OERR : 1;
    unsigned FERR : 1;
    unsigned : 2;
    unsigned CREN : 1;
    unsigned : 2;
    unsigned SPEN : 1;
} RCSTAbits_t;
extern volatile RCSTAbits_t RCSTAbits;

#endif

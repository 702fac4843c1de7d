/* Definitions of the stand-in registers so that the PIC layer also links on the host when
 * syntax-checked with -DHOST_CHECK_PIC. */
#include "pic18f4431_regs.h"
volatile uint8_t OSCCON, INTCON, INTCON2, PIE1, PIR1, PIE3, PIR3, IPR1, RCON;
volatile uint8_t TRISA, TRISB, TRISC, TRISD, TRISE, ANSEL0, ANSEL1, LATD;
volatile uint8_t T1CON, TMR1H, TMR1L, T5CON, TMR5H, TMR5L, PR5H, PR5L;
volatile uint8_t PTCON0, PTCON1, PTPERL, PTPERH, PDC0L, PDC0H, PDC1L, PDC1H, PDC2L, PDC2H,
    PWMCON0, PWMCON1, OVDCOND, OVDCONS, SEVTCMPL, SEVTCMPH, DTCON, FLTCONFIG;
volatile uint8_t ADCON0, ADCON1, ADCON2, ADCON3, ADCHS, ADRESH, ADRESL;
volatile uint8_t TXSTA, RCSTA, BAUDCON, SPBRG, SPBRGH, TXREG, RCREG;
volatile PIR1bits_t PIR1bits;
volatile PIR3bits_t PIR3bits;
volatile ADCON0bits_t ADCON0bits;
volatile RCSTAbits_t RCSTAbits;

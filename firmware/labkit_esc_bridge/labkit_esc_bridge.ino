// labkit_esc_bridge.ino - drive a hobby ESC from labkit's Pololu SMC driver
// (protocol: docs/reference/devices-tach-motor.md, PROTOCOLS 3.3)
//
// USB serial 115200 8N1 in, RC servo pulses out (pin 9, 50 Hz, 1000-2000 us). The sketch
// speaks a subset of the Pololu Simple Motor Controller compact protocol, so labkit's
// `esc_bridge` driver (the SMC driver restricted) runs it:
//
//   83           exit safe start
//   85 lo hi     speed = lo + 32*hi, 0..3200 -> pulse 1000..2000 us (one direction)
//   86 lo hi     reverse: unidirectional ESC -> 1000 us
//   92 n         brake -> 1000 us
//   E0           stop -> 1000 us, safe start armed again
//   A1 id        get variable: 0 error status, 20 target speed, 21 speed, 23 VIN mV,
//                127 reset flags; answers 2 bytes little-endian (other ids: 0)
//
// Any command byte has bit 7 set, data bytes are < 0x80. Errors (bits as on the SMC):
// 0 safe-start violation, 2 serial (format) error, 3 command timeout. Any error forces
// 1000 us until 83 arrives. No valid command for 500 ms -> command timeout.
// Debug lines on the same port (ASCII < 0x80, so they cannot collide): "P <us>", "ARM",
// "STOP", "?" -> "OK ..." / "ERR ...".
//
// The pulse is 1000 us from the first line of setup(): an ESC that sees full throttle while
// arming starts its throttle calibration. Opening the port resets the Arduino (DTR), the
// pulses stop for ~1-2 s and the ESC may disarm: labkit expects that.
//
// The pulses come from Timer1 compare interrupts (0.5 us steps, as the Servo library does it)
// but not from the Servo library: Servo is not part of the Arduino AVR core (the sketch must
// build from the core alone, as CI does) and its constructor presets 1500 us, half throttle.
// (Hardware fast PWM on OC1A, mode 14, would be jitter-free, but simavr 1.6, which CI runs
// the sketch on, simulates mode 14 as phase-correct PWM: simavr bug #579.) The AVR
// watchdog (500 ms) resets a hung sketch; a reset turns pin 9 into an input, so the ESC
// sees no pulses at all and cuts the motor, as it does on signal loss.

#include <avr/wdt.h>

#define ESC_PIN 9                // PB1
#define VIN_PIN A0            // optional divider to the battery; VIN_MV_PER_COUNT scales it
#define VIN_MV_PER_COUNT 0    // e.g. 29 for a 1:5.7 divider at 5 V reference; 0: not wired
#define TIMEOUT_MS 500

int target = 0;                 // 0..3200
int running = 0;                // what the pulse shows
bool safeStart = true;
unsigned int errors = 1;        // bit 0: safe start at power-up
unsigned int resetFlags = 0x0C;
unsigned long lastCommandMs = 0;
byte packet[3];
byte packetLen = 0;
byte need = 0;
char debugLine[24];
byte debugLen = 0;

int pulseFor(int speed) { return 1000 + (long)speed * 1000L / 3200L; }

volatile unsigned int highTicks = 2000;  // pulse width in 0.5 us ticks (2000 = 1000 us)

// Timer1 runs free at 0.5 us per tick; each compare match ends or starts a pulse on pin 9
// and schedules the next edge, 20 ms (40 000 ticks) per period.
ISR(TIMER1_COMPA_vect) {
  static bool high = false;
  static unsigned int width = 2000;
  if (!high) {
    PORTB |= _BV(PORTB1);
    width = highTicks;
    OCR1A += width;
  } else {
    PORTB &= ~_BV(PORTB1);
    OCR1A += 40000U - width;
  }
  high = !high;
}

void escWriteMicroseconds(int us) {
  if (us < 1000) us = 1000;
  if (us > 2000) us = 2000;
  noInterrupts();
  highTicks = (unsigned int)us * 2;     // used from the next pulse on
  interrupts();
}

void escBegin() {
  digitalWrite(ESC_PIN, LOW);
  pinMode(ESC_PIN, OUTPUT);
  TCCR1A = 0;                    // normal mode, pin 9 driven by the interrupt
  TCCR1B = _BV(CS11);            // prescaler 8: 0.5 us ticks
  OCR1A = TCNT1 + 200;
  TIFR1 = _BV(OCF1A);
  TIMSK1 |= _BV(OCIE1A);
}

void apply() {
  running = errors ? 0 : target;
  escWriteMicroseconds(pulseFor(running));
}

void setError(byte bit) { errors |= (1u << bit); apply(); }

void sendVariable(unsigned int value) { Serial.write(value & 0xFF); Serial.write(value >> 8); }

unsigned int variable(byte id) {
  switch (id) {
    case 0: return errors;
    case 20: return target;
    case 21: return running;
    case 23: return (unsigned int)(analogRead(VIN_PIN) * (long)VIN_MV_PER_COUNT);
    case 127: return resetFlags;
    default: return 0;
  }
}

byte dataLength(byte cmd) {
  switch (cmd) {
    case 0x83: case 0xE0: return 0;
    case 0x92: case 0xA1: return 1;
    case 0x85: case 0x86: return 2;
    default: return 255;        // not in the subset
  }
}

void execute() {
  byte cmd = packet[0];
  lastCommandMs = millis();
  if (cmd == 0x83) {
    safeStart = false;
    errors &= ~((1u << 0) | (1u << 2) | (1u << 3));
    apply();
  } else if (cmd == 0x85 || cmd == 0x86) {
    int speed = packet[1] + 32 * packet[2];
    target = (cmd == 0x85) ? min(speed, 3200) : 0;
    if (safeStart && target) setError(0); else apply();
  } else if (cmd == 0x92) {
    target = 0; apply();
  } else if (cmd == 0xE0) {
    target = 0; safeStart = true; apply();
  } else if (cmd == 0xA1) {
    sendVariable(variable(packet[1]));
  }
}

void debugCommand(char *text) {
  if (strcmp(text, "?") == 0) {
    Serial.print(F("OK pulse=")); Serial.print(pulseFor(running));
    Serial.print(F(" errors=")); Serial.print(errors); Serial.print('\n');
  } else if (strcmp(text, "ARM") == 0) {
    packet[0] = 0x83; execute(); Serial.print(F("OK\n"));
  } else if (strcmp(text, "STOP") == 0) {
    packet[0] = 0xE0; execute(); Serial.print(F("OK\n"));
  } else if (text[0] == 'P' && text[1] == ' ' && atoi(text + 2) >= 1000 && atoi(text + 2) <= 2000) {
    int speed = (long)(atoi(text + 2) - 1000) * 32L / 10L;
    packet[0] = 0x85; packet[1] = speed & 0x1F; packet[2] = speed >> 5;
    execute(); Serial.print(F("OK\n"));
  } else {
    Serial.print(F("ERR bad command\n"));
  }
}

void receive(byte b) {
  if (b & 0x80) {                       // a command byte starts a new packet
    if (packetLen) setError(2);            // the previous one was cut short
    need = dataLength(b);
    if (need == 255) { packetLen = 0; setError(2); return; }
    packet[0] = b; packetLen = 1;
  } else if (packetLen) {
    packet[packetLen++] = b;
  } else {                              // ASCII outside a packet: the debug line protocol
    if (b == '\n') { debugLine[debugLen] = '\0'; if (debugLen) debugCommand(debugLine); debugLen = 0; }
    else if (b != '\r' && debugLen < sizeof(debugLine) - 1) debugLine[debugLen++] = b;
    return;
  }
  if (packetLen == need + 1) { execute(); packetLen = 0; }
}

void setup() {
  byte mcusr = MCUSR; MCUSR = 0;
  wdt_disable();                        // a watchdog reset leaves it running: stop it first
  escBegin();                           // 1000 us pulses before anything else
  if (mcusr & (1 << WDRF)) resetFlags = 0x24;
  else if (mcusr & (1 << EXTRF)) resetFlags = 0x04;
  else if (mcusr & ((1 << PORF) | (1 << BORF))) resetFlags = 0x0C;
  else resetFlags = 0x14;
  Serial.begin(115200);                 // no banner: the port carries binary replies
  lastCommandMs = millis();
  wdt_enable(WDTO_500MS);
}

void loop() {
  wdt_reset();
  while (Serial.available()) receive(Serial.read());
  if (!(errors & (1u << 3)) && millis() - lastCommandMs > TIMEOUT_MS) setError(3);
}

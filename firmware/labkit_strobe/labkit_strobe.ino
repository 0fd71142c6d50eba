// labkit_strobe.ino - a stroboscope locked to the rotor (protocol: docs/reference/devices-strobe.md)
//
// ATmega328P (Uno/Nano, 16 MHz). The rotor's once-per-revolution pulse (active low, e.g. an
// optical sensor with a pull-up) goes to pin 8 (ICP1, PB0); the LED gate driver to pin 9
// (OC1A, PB1). Timer1 runs free at prescaler 1 (62.5 ns per tick, wraps every 4.096 ms,
// extended to 32 bits by counting overflows). Input capture time-stamps every falling edge in
// hardware; the flash is switched on and off by output compare in hardware, so a flash's
// start is placed to the timer tick whatever the interrupts are doing.
//
// Locking. Flash n falls at rotor position P_n (revolutions since some edge; P_{n+1} =
// P_n + m + dphi). Each flash is scheduled from the last captured edge t_k with the last
// measured period T: t = t_k + (P_n - k) * T. With dphi = D*m*T/(1 - D*T) (T in s) the rotor
// angle seen at successive flashes advances by D revolutions per second: the apparent
// frequency is exactly the commanded offset D whatever the rotor's speed does, and the
// strobe frequency is (f_rot - D)/m. A flash closer than LEAD_TICKS to its edge is scheduled
// from the edge before (at up to T + LEAD_TICKS).
//
// Lock: 4 periods in a row within 1/16 of the one before. Lost when a period leaves that
// band or the next edge is overdue by T/16; the lamp is dark until locked again. An edge
// sooner than 5/8 T after the last one is noise and ignored (flag N). No edge for 4 T
// (at most 1 s): no pulses (flag Z), the period is forgotten.
//
// Interrupts. The end compare of a flash can only be written once it has started: an OCR1B
// interrupt PRE_TICKS before the flash waits for the start and writes it at once (the start's
// own OCR1A interrupt is the fallback; if it comes too late the flash is ended in software
// and flagged S). An edge captured while a flash is armed or on is only stored; it is
// processed when the flash ends, so the capture interrupt never holds up a flash. Timer0's
// millis() interrupt is off (the uptime comes from Timer1). A watchdog (0.5 s) resets a hung
// sketch: the pins become inputs and the gate's pull-down keeps the LED dark.
//
// Serial 115200 8N1, LF-terminated commands, each answered "OK" or "ERR <text>":
//   OFFSET <hz>   apparent frequency D, -100..100 (default 0.5)
//   WIDTH <us>    flash length, 1..1000 us (default 20); at most T/4 is used (flag W)
//   DIV <m>       flash every m-th revolution, 1..100 (default 1)
//   OFF / ON      lamp off / on (default on)
//   RATE <hz>     status lines per second, 1..50 (default 1)
//   ID?           -> "ID labkit-strobe <ver>"
// Status line every 1/RATE s:
//   S,<seq>,<t_ms>,<f_rot_hz>,<f_strobe_hz>,<phase_deg>,<flags>
//   f_rot, f_strobe: mean over the window's revolutions / flash intervals (0 when none);
//   phase: rotor angle after the edge at the window's last flash (0-360);
//   flags: 0 ok, else letters: Z no pulses, L not locked, N noise pulse rejected,
//          X lamp off by command, W width cut to T/4, R offset too large for this speed
//          (|dphi| > 1/4 rev), O rotor too fast (> 4 kHz) or too slow (< 5 Hz),
//          M a flash was missed (scheduled too late), S a flash was stretched (its end
//          was held up by another interrupt: only widths of a few us).
// Boot banner: "# labkit-strobe <ver> offset=<hz> width=<us> div=<m> rate=<hz>".

#include <avr/wdt.h>

#define VERSION "1.0"
#define TICKS_PER_S 16000000.0
#define LEAD_TICKS 2400UL          // 150 us: capture ISR latency + its arithmetic, with margin
#define MIN_ARM_TICKS 300          // a compare armed closer than this may be missed
#define ARM_WINDOW 45056L          // 0xB000: OCR1A is 16 bits; arm only within this
#define MIN_PERIOD 4000UL          // 4 kHz
#define MAX_PERIOD 3200000UL       // 5 Hz
#define LOCK_PERIODS 4
#define MID_PERIOD 0x8000          // OCR1B: the mid-period housekeeping
#define PRE_TICKS 400              // a flash's end compare is set by an interrupt this long
                                   // before it that waits there for the start (TIMER1_COMPB)

enum FlashState { IDLE, PENDING, ARMED, ON };

// ---- shared with the interrupts --------------------------------------------------------
volatile uint16_t ovfCount = 0;
volatile uint32_t lastEdge = 0;        // extended ticks of the last accepted edge
volatile uint32_t periodTicks = 0;     // last period (0: unknown)
volatile bool haveEdge = false;
volatile byte goodPeriods = 0;
volatile bool locked = false;
// the next flash falls posRevs + posFrac / 2^32 revolutions after lastEdge
volatile int16_t posRevs = 0;
volatile uint32_t posFrac = 0;
// flash to flash: incWhole + incFrac / 2^32 = m + dphi revolutions (computed by loop())
volatile byte incWhole = 1;
volatile uint32_t incFrac = 0;
volatile bool rangeOk = true;          // |dphi| <= 1/4 revolution
volatile uint32_t target = 0;          // extended ticks of the pending flash
volatile uint16_t flashWidth = 320;    // ticks, after the T/4 cut
volatile byte state = IDLE;
volatile bool preArmed = false;       // OCR1B is set just before a short flash
volatile bool edgeDeferred = false;    // an edge captured while a flash was armed or on
volatile uint32_t deferredEdge = 0;
volatile bool lastFlashValid = false;  // for the strobe frequency: flash to flash in lock
volatile bool haveFlashed = false;     // lastFlashT/lastPhase hold a flash
volatile uint32_t lastFlashT = 0;
volatile uint32_t lastPhase = 0;       // 2^-32 rev
// window statistics (reset by the status line)
volatile uint16_t winRevs = 0;
volatile uint32_t winRevTicks = 0;
volatile uint16_t winFlashes = 0;
volatile uint32_t winFlashTicks = 0;
volatile byte winFlags = 0;            // bits below, sticky for one window
#define F_NOISE 1
#define F_MISSED 2
#define F_WIDTH 4
#define F_RANGE 8
#define F_SPEED 16
#define F_UNLOCKED 32
#define F_NOPULSE 64
#define F_LATE 128

// settings (written by loop with interrupts off)
volatile float offsetHz = 0.5;
volatile byte divider = 1;
volatile uint16_t widthTicks = 320;    // 20 us: ended by hardware even when interrupts collide
volatile bool lampOn = true;
unsigned int rateHz = 1;

unsigned long seq = 0;
unsigned long nextStatusMs = 0;
char line[32];
byte lineLen = 0;

static void onEdge(uint32_t t);

// Extended timer value; call with interrupts off. An overflow whose interrupt is pending
// belongs to a small TCNT1.
static inline uint32_t nowTicks() {
  uint16_t lo = TCNT1;
  uint16_t hi = ovfCount;
  if ((TIFR1 & _BV(TOV1)) && lo < 0x8000) hi++;
  return ((uint32_t)hi << 16) | lo;
}

static void cancelFlash() {
  if (state == PENDING || state == ARMED) {
    TCCR1A = 0;                 // OC1A disconnected: the pin follows PORTB1 = 0
    state = IDLE;
  }                             // a flash already on ends at its own compare
  if (preArmed) {
    preArmed = false;
    OCR1B = MID_PERIOD;
  }
}

static void unlock() {
  if (locked) winFlags |= F_UNLOCKED;
  locked = false;
  goodPeriods = 0;
  lastFlashValid = false;
  cancelFlash();
}

// ticks from lastEdge to the next flash (float: 24 bits of posFrac are plenty)
static uint32_t delayTicks() {
  uint32_t T = periodTicks;
  return (uint32_t)posRevs * T + (uint32_t)((float)posFrac * (float)T * 2.3283064e-10f + 0.5f);
}

static void advance() {                  // the next flash: m + dphi revolutions on
  uint32_t f = posFrac + incFrac;
  posRevs += incWhole + (f < posFrac ? 1 : 0);
  posFrac = f;
}

static void tryArm(uint32_t now) {
  if (state != PENDING) return;
  int32_t ahead = (int32_t)(target - now);
  if (ahead < MIN_ARM_TICKS) {           // too late: skip this flash
    state = IDLE;
    advance();
    winFlags |= F_MISSED;
    return;
  }
  if (ahead < ARM_WINDOW) {
    OCR1A = (uint16_t)target;
    TCCR1A = _BV(COM1A1) | _BV(COM1A0);  // set OC1A on compare match
    state = ARMED;
    if (ahead > PRE_TICKS + MIN_ARM_TICKS) {
      OCR1B = (uint16_t)(target - PRE_TICKS);   // wake up just before it: see TIMER1_COMPB
      preArmed = true;
    }
  }
}

// Schedule the next flash from lastEdge when it falls before the next edge (+ lead).
static void scheduleFromEdge() {
  uint32_t d = delayTicks();
  if (d >= periodTicks + LEAD_TICKS) { state = IDLE; return; }
  target = lastEdge + d;
  state = PENDING;
  tryArm(nowTicks());
}

// On (re)gaining the lock at edge t (period T): place the next flash so that the apparent
// angle goes on as if the lamp had never stopped, phase + D * (time since the last flash).
// With x revolutions after t, the flash at t + x T must show angle phi + D x T = frac(x):
// x = phi / (1 - D T). Floats are fine here (once per lock; no flash is armed).
static void resumePhase(uint32_t t, uint32_t T) {
  posRevs = 0;
  if (!haveFlashed) return;               // the first lock: from the fraction kept
  float ts = (float)T / TICKS_PER_S;
  float turns = offsetHz * ((float)(t - lastFlashT) / TICKS_PER_S) + (float)lastPhase * 2.3283064e-10f;
  turns -= floor(turns);
  float x = turns / (1.0f - offsetHz * ts);
  if (x >= 1.0f) { posRevs = 1; x -= 1.0f; }
  if (x < 0.0f) x = 0.0f;
  posFrac = (uint32_t)(x * 4294967296.0f);
}

ISR(TIMER1_CAPT_vect) {
  uint16_t icr = ICR1;
  uint16_t hi = ovfCount;
  if ((TIFR1 & _BV(TOV1)) && icr < 0x8000) hi++;
  uint32_t t = ((uint32_t)hi << 16) | icr;
  if (state == ARMED || state == ON) {
    // A flash is starting about now (it was scheduled from the edge before): keep this
    // interrupt short so the flash's compare interrupt programs its end in time; the edge
    // is processed when the flash ends (or by the next housekeeping if it is cancelled).
    if (edgeDeferred) winFlags |= F_NOISE;   // two edges within one flash: one is noise
    else { deferredEdge = t; edgeDeferred = true; }
    return;
  }
  onEdge(t);
}

// Everything about a captured edge (interrupts off); out of line so that the capture
// interrupt's prologue is short.
static void __attribute__((noinline)) onEdge(uint32_t t) {
  winFlags &= ~F_NOPULSE;
  if (!haveEdge) {
    lastEdge = t;
    haveEdge = true;
    periodTicks = 0;
    goodPeriods = 0;
    return;
  }
  uint32_t dt = t - lastEdge;
  uint32_t prev = periodTicks;
  if (locked && dt < prev / 2 + prev / 8) {  // sooner than 5/8 T: a noise pulse
    // (only when locked: unlocked, every edge counts, so a rotor found at twice the rate
    // of a remembered period is not locked onto every other pulse)
    winFlags |= F_NOISE;
    return;
  }
  lastEdge = t;
  periodTicks = dt;
  winRevs++;
  winRevTicks += dt;
  uint32_t diff = dt > prev ? dt - prev : prev - dt;
  bool inRange = dt >= MIN_PERIOD && dt <= MAX_PERIOD;
  if (!inRange) winFlags |= F_SPEED;
  if (!prev || !inRange || diff > prev / 16) {
    unlock();
    return;
  }
  bool wasLocked = locked;
  if (!wasLocked) {
    if (++goodPeriods < LOCK_PERIODS) return;
    locked = true;
    resumePhase(t, dt);
  } else if (--posRevs < 0) {
    posRevs = 0;                  // no flash consumed it (lamp off, offset out of range)
  }
  if (state == ARMED || state == ON) return;  // (short: this flash may be starting now)
  uint16_t w = widthTicks;
  if (w > (dt >> 2)) { w = dt >> 2; winFlags |= F_WIDTH; }
  flashWidth = w;
  if (!rangeOk) {
    winFlags |= F_RANGE;
    cancelFlash();
    return;
  }
  if (!lampOn) return;
  uint32_t d = delayTicks();
  if (state == PENDING && d < LEAD_TICKS) {          // keep the target set from the edge before
    tryArm(nowTicks());
    return;
  }
  state = IDLE;
  while (d < LEAD_TICKS) {                           // too close to this edge: a later one
    advance();
    if (wasLocked) winFlags |= F_MISSED;
    d = delayTicks();
  }
  scheduleFromEdge();
}

// The deferred edge, if any (interrupts off, no flash armed or on).
static void processDeferredEdge() {
  if (!edgeDeferred) return;
  edgeDeferred = false;
  onEdge(deferredEdge);      // schedules the next flash itself
}

static void endFlash() {
  TCCR1A = 0;
  state = IDLE;
  if (edgeDeferred) processDeferredEdge();
  else if (locked && lampOn) scheduleFromEdge();
}

// The bookkeeping of a flash that has just started, out of line: the compare interrupt's
// prologue then saves few registers and reaches the end compare within a few microseconds.
static void __attribute__((noinline)) flashStarted(bool ended) {
  if (lastFlashValid) {
    winFlashes++;
    winFlashTicks += target - lastFlashT;
  }
  lastFlashT = target;
  lastFlashValid = true;
  haveFlashed = true;
  lastPhase = posFrac;
  advance();
  if (ended) endFlash();
}

static void __attribute__((noinline)) flashEnded() { endFlash(); }

// The flash has just been switched on by the compare at ``start``: program its end (interrupts
// off). If TCNT1 may already be past the end, end it here.
static void startFlash(uint16_t start) {
  TCCR1A = _BV(COM1A1);                    // clear OC1A on the next match
  uint16_t width = flashWidth;
  OCR1A = start + width;
  state = ON;
  // the end compare is certain only if it was written before TCNT1 got there; if not
  // (this interrupt was held up by another), end the flash here
  bool late = (uint16_t)(TCNT1 - start) + 2 >= width;
  if (late) {
    while ((uint16_t)(TCNT1 - start) < width) {}
    PORTB &= ~_BV(PB1);                    // with OC1A disconnected the pin is PORTB1 = 0
    TCCR1A = 0;
    winFlags |= F_LATE;
  }
  flashStarted(late);
}

ISR(TIMER1_COMPA_vect) {
  uint16_t start = OCR1A;
  if ((uint16_t)(TCNT1 - start) > 0x4000) return;   // a match of an earlier OCR1A value
  if (state == ARMED) startFlash(start);
  else if (state == ON) flashEnded();
}

// Called from the overflow and mid-period interrupts with interrupts enabled again, so that a
// flash's compare interrupt is not held up: state is read and changed with them off.
static void housekeeping() {
  noInterrupts();
  uint32_t now = nowTicks();
  uint32_t last = lastEdge, T = periodTicks;
  // (an edge waiting for its interrupt, or deferred behind a flash, is not late)
  bool have = haveEdge && !edgeDeferred && !(TIFR1 & _BV(ICF1));
  interrupts();
  if (have) {
    uint32_t since = now - last;
    uint32_t zto = T ? 4 * T : 16000000UL;
    if (zto > 16000000UL) zto = 16000000UL;
    bool overdue = since > T + T / 16, stopped = since > zto;
    if (overdue || stopped) {
      noInterrupts();
      if (lastEdge == last && haveEdge && !edgeDeferred) {   // no edge came meanwhile
        if (stopped) {
          haveEdge = false;
          periodTicks = 0;
          winFlags |= F_NOPULSE;
        }
        if (locked || stopped) unlock();
      }
      interrupts();
    }
  }
  noInterrupts();
  if (state == IDLE || state == PENDING) processDeferredEdge();
  tryArm(nowTicks());
  interrupts();
}

ISR(TIMER1_OVF_vect) {
  ovfCount++;
  interrupts();
  housekeeping();
}

// Mid-period housekeeping, or (preArmed) the moment just before a flash: wait here,
// interrupts off, until the hardware has switched the lamp on, then set the end compare at
// once, so that even a 1 us flash is ended by the hardware.
ISR(TIMER1_COMPB_vect) {
  if (preArmed) {
    preArmed = false;
    OCR1B = MID_PERIOD;
    if (state == ARMED) {
      uint16_t start = OCR1A;
      while (!(TIFR1 & _BV(OCF1A)) && (int16_t)(TCNT1 - start) < 8) {}
      // (the match's own interrupt then finds OCR1A moved on and returns; TIFR1 is not
      // written: simavr 1.6 would clear every Timer1 flag, a pending overflow too)
      startFlash(start);
    }
    return;
  }
  interrupts();
  housekeeping();
}

// ---- host side: commands, status lines (labkit_strobe_host.h) ---------------------------
#include "labkit_strobe_host.h"

void setup() {
  MCUSR = 0;
  wdt_disable();                     // a watchdog reset leaves it running: stop it first
  Serial.begin(115200);
  pinMode(8, INPUT_PULLUP);
  digitalWrite(9, LOW);
  pinMode(9, OUTPUT);
  noInterrupts();
  TCCR1B = 0;                        // undo the core's PWM set-up of Timer1
  TCCR1A = 0;
  TCNT1 = 0;
  OCR1B = MID_PERIOD;                // mid-period housekeeping
  TIFR1 = 0xFF;
  TIMSK1 = _BV(ICIE1) | _BV(OCIE1A) | _BV(OCIE1B) | _BV(TOIE1);
  TCCR1B = _BV(ICNC1) | _BV(CS10);   // noise canceller, falling edge, prescaler 1
  TIMSK0 = 0;                        // no millis() interrupt to delay a flash's end: the
  interrupts();                      // status line times itself with Timer1 (uptimeMs)
  printBanner();
  nextStatusMs = uptimeMs() + 1000 / rateHz;
  wdt_enable(WDTO_500MS);            // a hung sketch resets: pin 9 becomes an input, the gate's
}                                    // pull-down keeps the LED dark

void loop() {
  wdt_reset();
  updateIncrement(false);
  readCommands();
  if ((long)(uptimeMs() - nextStatusMs) >= 0) {
    nextStatusMs += 1000 / rateHz;
    printStatus();
  }
}

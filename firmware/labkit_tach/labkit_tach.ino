// labkit_tach.ino - labkit pulse tachometer (protocol: docs/reference/devices-tach-motor.md, PROTOCOLS 2.3)
//
// An optical (reflective patch) or Hall sensor gives PPR pulses per revolution on pin 2
// (INT0 on an Uno/Nano). The interrupt time-stamps every pulse with micros(); once per
// output window the sketch prints the mean period of the pulses in that window:
//
//   T,<seq>,<t_ms>,<rpm>,<period_us>,<pulses>,<flags>\n        115200 8N1
//   rpm = 60e6 / (period_us * ppr)
//   flags: 0 ok | Z zero-speed timeout | O too fast (period < 50 us) | N glitch rejected or
//          missing pulse bridged (a period 1.5-4.5 times the last one counts as 2-4 periods)
//
// Host commands (LF-terminated): "PPR <n>", "RATE <hz>", "ZTO <ms>" -> "OK" or "ERR <text>",
// "ID?" -> "ID labkit-tach <ver>". Boot banner: "# labkit-tach <ver> ppr=.. rate=.. zto=..".
// Settings are not stored: after a reset the host (labkit) sends them again.
//
// micros() has 4 us resolution on a 16 MHz AVR: at 100 000 RPM and 1 PPR (600 us period)
// one period is +-0.7 %, the mean over a 100 ms window (166 pulses) far better.

#define VERSION "1.0"
#define PULSE_PIN 2            // INT0
#define MIN_PERIOD_US 50UL     // shorter mean period: flag O (about 1.2 million RPM at 1 PPR)
#define GLITCH_US 20UL         // an edge closer than this to the last one is noise: flag N

volatile unsigned long lastEdgeUs = 0;   // time of the last accepted edge
volatile unsigned long sumUs = 0;        // sum of periods in this window
volatile unsigned long count = 0;        // periods in this window
volatile bool haveEdge = false;          // lastEdgeUs is valid
volatile bool glitch = false;            // an edge was rejected in this window
volatile unsigned long lastDtUs = 0;     // last single period (0: unknown, e.g. after a stop)

unsigned int ppr = 1;
unsigned int rateHz = 10;
unsigned long ztoMs = 1000;
unsigned long seq = 0;
unsigned long nextOutputMs = 0;
float lastPeriodUs = 0;                  // 0: no period known
char line[32];
byte lineLen = 0;

void onPulse() {
  unsigned long now = micros();
  if (haveEdge) {
    unsigned long dt = now - lastEdgeUs;  // unsigned arithmetic survives the 70 min wrap
    if (dt < GLITCH_US) {
      glitch = true;
      return;
    }
    unsigned long prev = lastDtUs;
    if (prev && dt > prev + prev / 2) {
      if (dt < 4 * prev + prev / 2) {      // 1-3 pulses missing (a dirty patch): bridge them
        byte periods = 2;
        while (periods < 4 && dt > periods * prev + prev / 2) periods++;
        sumUs += dt;
        count += periods;
        glitch = true;
      } else {
        lastDtUs = 0;                      // a restart after a stop: time from this edge
      }
    } else {
      sumUs += dt;
      count++;
      lastDtUs = dt;
    }
  }
  lastEdgeUs = now;
  haveEdge = true;
}

void printBanner() {
  Serial.print(F("# labkit-tach " VERSION " ppr="));
  Serial.print(ppr);
  Serial.print(F(" rate="));
  Serial.print(rateHz);
  Serial.print(F(" zto="));
  Serial.print(ztoMs);
  Serial.print('\n');
}

void setup() {
  Serial.begin(115200);
  pinMode(PULSE_PIN, INPUT_PULLUP);
  attachInterrupt(digitalPinToInterrupt(PULSE_PIN), onPulse, FALLING);
  printBanner();
  nextOutputMs = millis() + 1000 / rateHz;
}

void reply(const __FlashStringHelper *text) { Serial.print(text); Serial.print('\n'); }

void handleCommand(char *cmd) {
  if (strcmp(cmd, "ID?") == 0) {
    reply(F("ID labkit-tach " VERSION));
    return;
  }
  char *space = strchr(cmd, ' ');
  if (space == NULL) { reply(F("ERR unknown command")); return; }
  *space = '\0';
  long value = atol(space + 1);
  if (strcmp(cmd, "PPR") == 0) {
    if (value < 1 || value > 64) { reply(F("ERR bad value")); return; }
    noInterrupts(); ppr = value; sumUs = 0; count = 0; haveEdge = false; lastDtUs = 0; interrupts();
    lastPeriodUs = 0;
  } else if (strcmp(cmd, "RATE") == 0) {
    if (value < 1 || value > 200) { reply(F("ERR bad value")); return; }
    rateHz = value;
  } else if (strcmp(cmd, "ZTO") == 0) {
    if (value < 10 || value > 10000) { reply(F("ERR bad value")); return; }
    ztoMs = value;
  } else {
    reply(F("ERR unknown command"));
    return;
  }
  reply(F("OK"));
}

void readCommands() {
  while (Serial.available()) {
    char c = Serial.read();
    if (c == '\r') continue;
    if (c == '\n') {
      line[lineLen] = '\0';
      if (lineLen) handleCommand(line);
      lineLen = 0;
    } else if (lineLen < sizeof(line) - 1) {
      line[lineLen++] = c;
    } else {
      lineLen = 0;   // too long: garbage, drop it
    }
  }
}

void printWindow() {
  noInterrupts();
  unsigned long s = sumUs, n = count, last = lastEdgeUs;
  bool have = haveEdge, noisy = glitch;
  sumUs = 0; count = 0; glitch = false;
  interrupts();

  float period = 0;
  char flags[4] = "";
  byte f = 0;
  if (n > 0) {
    period = (float)s / n;
    lastPeriodUs = period;
  } else if (lastPeriodUs > 0 && have && (micros() - last) / 1000UL <= ztoMs) {
    period = lastPeriodUs;               // slower than one pulse per window: repeat
  } else {
    lastPeriodUs = 0;
    flags[f++] = 'Z';
  }
  if (period > 0 && period < MIN_PERIOD_US) flags[f++] = 'O';
  if (noisy && flags[0] != 'Z') flags[f++] = 'N';
  flags[f] = '\0';
  float rpm = (period > 0 && flags[0] != 'Z') ? 60.0e6 / (period * ppr) : 0.0;

  Serial.print(F("T,"));
  Serial.print(seq++);
  Serial.print(',');
  Serial.print(millis());
  Serial.print(',');
  Serial.print(rpm, 1);
  Serial.print(',');
  Serial.print(period, 1);
  Serial.print(',');
  Serial.print(n);
  Serial.print(',');
  if (f == 0) Serial.print('0'); else Serial.print(flags);
  Serial.print('\n');
}

void loop() {
  readCommands();
  if ((long)(millis() - nextOutputMs) >= 0) {
    nextOutputMs += 1000 / rateHz;
    printWindow();
  }
}

// TMEye pan/tilt servo board: speaks docs/servo-ascii-protocol.md (version 1) over the USB serial port.
// Two hobby servos: pan on pin 9, tilt on pin 10. Calibration below: pulse width = centre + deg * us/deg.

#include <Servo.h>
#include <stdlib.h>
#include <string.h>

static const long BAUD = 115200;
static const int PAN_PIN = 9;
static const int TILT_PIN = 10;

// Per-axis calibration (measure with the mount: centre = looking straight ahead and level).
static const float PAN_CENTER_US = 1500.0;
static const float PAN_US_PER_DEG = 2000.0 / 180.0;  // negative to reverse the servo
static const float TILT_CENTER_US = 1500.0;
static const float TILT_US_PER_DEG = 2000.0 / 180.0;
static const float PAN_MIN_DEG = -90.0, PAN_MAX_DEG = 90.0;
static const float TILT_MIN_DEG = -30.0, TILT_MAX_DEG = 80.0;

static const int LINE_MAX = 40;

Servo panServo;
Servo tiltServo;
float panDeg = 0.0, tiltDeg = 0.0;
char line[LINE_MAX + 1];
int lineLen = 0;
bool overflow = false;

static float clampf(float v, float lo, float hi) { return v < lo ? lo : (v > hi ? hi : v); }

static void drive() {
  if (!panServo.attached()) panServo.attach(PAN_PIN);
  if (!tiltServo.attached()) tiltServo.attach(TILT_PIN);
  panServo.writeMicroseconds((int)(PAN_CENTER_US + panDeg * PAN_US_PER_DEG + 0.5));
  tiltServo.writeMicroseconds((int)(TILT_CENTER_US + tiltDeg * TILT_US_PER_DEG + 0.5));
}

// Parses a decimal number at *p, advancing p; false if there is none.
static bool parseNumber(char **p, float *out) {
  while (**p == ' ') (*p)++;
  char *end;
  double v = strtod(*p, &end);
  if (end == *p) return false;
  *p = end;
  *out = (float)v;
  return true;
}

static void reply2(const char *head, float a, float b) {
  Serial.print(head);
  Serial.print(a, 2);
  Serial.print(' ');
  Serial.println(b, 2);
}

static void handle(char *cmd) {
  if (strcmp(cmd, "H") == 0) {
    Serial.print("TMEYE-SERVO 1 ");
    Serial.print((int)PAN_MIN_DEG); Serial.print(' ');
    Serial.print((int)PAN_MAX_DEG); Serial.print(' ');
    Serial.print((int)TILT_MIN_DEG); Serial.print(' ');
    Serial.println((int)TILT_MAX_DEG);
  } else if (cmd[0] == 'P' && (cmd[1] == ' ' || cmd[1] == '\0')) {
    char *p = cmd + 1;
    float pan, tilt;
    if (!parseNumber(&p, &pan) || !parseNumber(&p, &tilt)) { Serial.println("ERR bad number"); return; }
    while (*p == ' ') p++;
    if (*p != '\0') { Serial.println("ERR bad number"); return; }
    panDeg = clampf(pan, PAN_MIN_DEG, PAN_MAX_DEG);
    tiltDeg = clampf(tilt, TILT_MIN_DEG, TILT_MAX_DEG);
    drive();
    Serial.println("OK");
  } else if (strcmp(cmd, "Q") == 0) {
    reply2("POS ", panDeg, tiltDeg);
  } else if (strcmp(cmd, "D") == 0) {
    panServo.detach();
    tiltServo.detach();
    Serial.println("OK");
  } else {
    Serial.println("ERR unknown command");
  }
}

void setup() {
  Serial.begin(BAUD);
  drive();  // home
}

void loop() {
  while (Serial.available() > 0) {
    char c = (char)Serial.read();
    if (c == '\r') continue;
    if (c != '\n') {
      if (lineLen < LINE_MAX) line[lineLen++] = c; else overflow = true;
      continue;
    }
    line[lineLen] = '\0';
    if (overflow) Serial.println("ERR line too long");
    else if (lineLen > 0) handle(line);
    lineLen = 0;
    overflow = false;
  }
}

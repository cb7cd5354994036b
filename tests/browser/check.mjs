// The browser tests' tally: check(ok, what, detail) prints "ok" or "FAIL" for one expectation and
// counts it; summary() is the closing line and the exit code.
let passed = 0;
let failed = 0;

export function check(ok, what, detail = '') {
  if (ok) {
    passed += 1;
    console.log(`ok   ${what}`);
  } else {
    failed += 1;
    console.log(`FAIL ${what}${detail ? `: ${detail}` : ''}`);
  }
}

// Prints "N passed, M failed" and `where`, and returns the exit code (1 when anything failed).
export function summary(where = '') {
  console.log(`\n${passed} passed, ${failed} failed${where ? `; ${where}` : ''}`);
  return failed ? 1 : 0;
}

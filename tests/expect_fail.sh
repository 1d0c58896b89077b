#!/usr/bin/env bash
# expect_fail.sh REGEX CMD...: CMD must exit non-zero and print exactly one line on stderr
# matching REGEX (extended grep).
regex=$1; shift
err=$("$@" 2>&1 >/dev/null); code=$?
lines=$(printf '%s\n' "$err" | grep -c .)
if [ $code -eq 0 ]; then echo "expected failure, got exit 0; stderr: $err"; exit 1; fi
if [ "$lines" -ne 1 ]; then echo "expected one line on stderr, got $lines: $err"; exit 1; fi
if ! printf '%s\n' "$err" | grep -Eq -- "$regex"; then echo "stderr '$err' does not match '$regex'"; exit 1; fi
echo "ok (exit $code): $err"

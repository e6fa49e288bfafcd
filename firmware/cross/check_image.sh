#!/bin/sh
# Fails if the image links anything that allocates or unwinds; prints sizes.
#   check_image.sh IMAGE.elf STAMP
set -eu
elf="$1"
stamp="$2"
rm -f "$stamp"
forbidden='^(malloc|free|calloc|realloc|_malloc_r|_free_r|_calloc_r|_realloc_r|_sbrk|_sbrk_r|__cxa_throw|__cxa_allocate_exception|__cxa_begin_catch|__gxx_personality_v0|__aeabi_unwind_cpp_pr[0-9]|_Unwind_[A-Za-z_]*|_Zn[wa][jm].*|_Zd[la]Pv.*)$'
found=$(arm-none-eabi-nm "$elf" | awk '{print $NF}' | grep -E "$forbidden" || true)
if [ -n "$found" ]; then
  echo "FAIL: $elf links heap or unwinding symbols:" >&2
  echo "$found" | sed 's/^/  /' >&2
  exit 1
fi
arm-none-eabi-size -A "$elf" | awk -v elf="$(basename "$elf")" '
  $1 ~ /^\.(vectors|text|rodata|init_array|data)$/ { flash += $2 }
  $1 ~ /^\.(data|bss|fast_bss|stack|noinit)$/ { ram += $2 }
  $1 == ".fast_bss" || $1 == ".stack" { fast += $2 }
  END { printf "%s: flash %d bytes, RAM %d bytes (of which fast RAM %d: control state + stack)\n", elf, flash, ram, fast }'
arm-none-eabi-size "$elf"
touch "$stamp"

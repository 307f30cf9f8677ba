# Sourced by harness/mitsuba_mesh.sh and harness/equal_time.sh (with $root set): Mitsuba's virtual
# environment ($venv: MITSUBA_VENV, default target/mitsuba-venv, with harness/requirements.txt)
# and, unless given, DRJIT_LIBLLVM_PATH for the llvm_ad_rgb variant: the newest libLLVM from 16
# on (Dr.Jit refuses 14, and with Debian 12's 15 its JIT fails on `fminimum`; Debian 12 has
# `apt-get install libllvm19`). Then the ptui binaries the harness calls, built in release.
venv="${MITSUBA_VENV:-$root/target/mitsuba-venv}"
if [ ! -x "$venv/bin/python" ]; then
    python3 -m venv "$venv"
fi
"$venv/bin/pip" install -q -r "$root/harness/requirements.txt"
if [ -z "${DRJIT_LIBLLVM_PATH:-}" ]; then
    for v in 22 21 20 19 18 17 16; do
        for lib in /usr/lib/x86_64-linux-gnu/libLLVM.so.$v.1 /usr/lib/x86_64-linux-gnu/libLLVM-$v.so \
            /usr/lib/llvm-$v/lib/libLLVM.so.1 /usr/lib/llvm-$v/lib/libLLVM-$v.so; do
            if [ -e "$lib" ]; then
                export DRJIT_LIBLLVM_PATH="$lib"
                break 2
            fi
        done
    done
fi
(cd "$root" && cargo build --release -q -p ptui -p xtask)
export PTUI_XTASK="${PTUI_XTASK:-$root/target/release/xtask}"

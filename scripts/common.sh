# Shell functions the scripts share (sourced, not run): installing Debian packages where
# they are missing, and timing programs side by side.

# apt_install WHY PACKAGE...: installs the packages with apt-get (as root, or with sudo),
# saying why; nothing when none is given.
apt_install() {
    local why=$1
    shift
    [ $# -gt 0 ] || return 0
    echo "== installing $* ($why)"
    local sudo=""
    [ "$(id -u)" -eq 0 ] || sudo="sudo"
    $sudo apt-get update -qq
    DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq "$@" > /dev/null
}

# timed TAG COMMAND...: runs the command (its standard output discarded) and prints
# "TAG SECONDS", its whole-process wall time.
timed() {
    local tag=$1
    shift
    local s e
    s=$(date +%s.%N)
    "$@" > /dev/null || { echo "failed: $*" >&2; return 1; }
    e=$(date +%s.%N)
    echo "$tag $(awk -v s="$s" -v e="$e" 'BEGIN { print e - s }')"
}

# medians NAME: reads "d SECONDS" and "p SECONDS" lines (deepfield's and a peer's runs) and
# prints NAME, each one's fastest and median, and the ratio of the medians.
medians() {
    sort -k1,1 -k2,2n | awk -v name="$1" '
        {t[$1 "," (++n[$1])] = $2}
        END {
            df = t["d,1"]; dm = t["d," int((n["d"] + 1) / 2)]
            pf = t["p,1"]; pm = t["p," int((n["p"] + 1) / 2)]
            printf "%-12s %10.2f /%7.2f s %10.2f /%7.2f s %8.2f\n", name, df, dm, pf, pm, dm / pm
        }'
}

# peer_setup HERE [DEEPFIELD]: for a side-by-side benchmark, sets df (the deepfield binary,
# the release build by default, built if missing) and out (a scratch folder removed on
# exit), and prints the CPU and the SIMD level deepfield runs with.
peer_setup() {
    df=${2:-$1/target/release/deepfield}
    [ -x "$df" ] || (cd "$1" && cargo build --release --locked)
    out=$(mktemp -d)
    trap 'rm -rf "$out"' EXIT
    local simd
    simd=$("$df" render "$1/scenes/bench-e14.toml" --size 8x6 -o "$out/s.png" --stats -q | awk '/^simd/ {$1=""; print substr($0, 2)}')
    echo "CPU: $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2- | sed 's/^ //'); deepfield SIMD: $simd"
}

#!/usr/bin/env bash
# What a real `heist-server serve` costs with its players in other processes: the server alone on CPU 0,
# N bot pairs (`heist-server join`, one process each) on CPU 1, and the server's own figures from its
# /metrics, scraped twice SECONDS apart once every player is in (docs/performance.md, issue 48).
#
#   cargo build --release -p heist_server --features bots
#   scripts/serve-load.sh [SESSIONS=10] [SECONDS=20] [BINARY=target/release/heist-server]
#
# Loopback only (127.0.0.1:5800 for the game and tokens, :9790 for metrics). A pair creates its session
# through the token endpoint, which lets one address create 10 at once and one more every 6 s: past 10
# sessions each waits its turn (a minute for each 10 more).
set -euo pipefail
sessions=${1:-10}
seconds=${2:-20}
bin=${3:-target/release/heist-server}
game=127.0.0.1:5800
metrics=127.0.0.1:9790
work=$(mktemp -d)
# At the end every process this started goes at once (a served server would drain its heists first).
pids=()
trap 'kill -9 "${pids[@]}" 2>/dev/null; rm -rf "$work"' EXIT

taskset -c 0 "$bin" serve --bind "$game" --metrics "$metrics" --max-sessions "$sessions" >"$work/serve.log" 2>&1 &
pids+=($!) && disown
for _ in $(seq 100); do curl -sf "http://$metrics/healthz" >/dev/null && break; sleep 0.1; done

for i in $(seq "$sessions"); do
    # Each bot its own seat cache: two bots of one role on one address must not take each other's seats.
    mkdir -p "$work/$i/vive" "$work/$i/phantom"
    code=""
    for _ in $(seq 30); do
        XDG_CACHE_HOME="$work/$i/vive" taskset -c 1 "$bin" join "$game" --create --role vive --rounds 1000 \
            >"$work/$i/vive.log" 2>&1 &
        vive=$!
        pids+=("$vive") && disown "$vive"
        for _ in $(seq 400); do
            code=$(grep -o 'join code: [A-Z0-9-]*' "$work/$i/vive.log" | cut -d' ' -f3 || true)
            [ -n "$code" ] && break
            kill -0 "$vive" 2>/dev/null || break
            sleep 0.25
        done
        [ -n "$code" ] && break
        # Refused (the endpoint's creation limit for one address): wait as it says, then again.
        grep -q 'too many new sessions' "$work/$i/vive.log" || break
        sleep 6
    done
    [ -n "$code" ] || { echo "session $i: no join code" >&2; cat "$work/$i/vive.log" >&2; exit 1; }
    XDG_CACHE_HOME="$work/$i/phantom" taskset -c 1 "$bin" join "$game" --code "$code" --role phantom \
        --rounds 1000 >"$work/$i/phantom.log" 2>&1 &
    pids+=($!) && disown
done
want="ok: $sessions sessions, $((sessions * 2)) players"
for _ in $(seq 300); do [ "$(curl -s "http://$metrics/healthz")" = "$want" ] && break; sleep 0.1; done
[ "$(curl -s "http://$metrics/healthz")" = "$want" ] || { echo "not every player came in" >&2; exit 1; }

sleep 2
first=$(curl -s "http://$metrics/metrics")
sleep "$seconds"
second=$(curl -s "http://$metrics/metrics")
value() { awk -v n="$1" '$1 == n { print $2 }' <<<"$2"; }
delta() { awk -v a="$(value "$1" "$first")" -v b="$(value "$1" "$second")" 'BEGIN { print b - a }'; }
cpu=$(delta heist_tick_cpu_seconds_total)
updates=$(delta heist_tick_seconds_count)
sent=$(delta heist_sent_bytes_total)
received=$(delta heist_received_bytes_total)
awk -v cpu="$cpu" -v n="$updates" -v s="$seconds" -v sessions="$sessions" -v sent="$sent" -v rec="$received" 'BEGIN {
    printf "%d sessions, %d players, %s s: server CPU %.1f %% of a core, %.1f us a session per game tick (60 a second)\n",
        sessions, 2 * sessions, s, 100 * cpu / s, 1e6 * cpu / s / 60 / sessions
    printf "shard updates %.0f a second, %.0f us CPU each; per player down %.0f B/s, up %.0f B/s\n",
        n / s, 1e6 * cpu / n, sent / s / (2 * sessions), rec / s / (2 * sessions)
}'

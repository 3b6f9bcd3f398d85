#!/usr/bin/env bash
# Move an unfinished run folder (a reproduction, a training run) between machines through git
# (issue 18; docs/training.md, "Runs that move between machines").
#
#   scripts/carry.sh pack RUN FILE     RUN's resumable state as one file (tar, xz)
#   scripts/carry.sh unpack FILE RUN   lay it out again as RUN (which must not exist)
#
# A packed state over CARRY_PART_BYTES (4,500,000 bytes: the repository takes no file over
# 5 MB) is written as FILE.part00, FILE.part01, ... in its stead, which unpack joins again (a
# finished paper-light seed: two final networks, six evaluation journals, its report: 7.3 MB).
#
# pack keeps every file of RUN but TensorBoard logs, locks and temporary files, and for each
# training run folder in it (one holding checkpoint.pt): a finished run (convergence.json
# written) as its final network alone (vgs export-policy RUN --out RUN: policy.pt, 2.4 MB with
# the light backbone), an unfinished one with its checkpoint (4.9-7.4 MB for a 5000-grasp light
# run). `vgs train` and `vgs reproduce` take a finished run kept that way as done and evaluate
# its policy.pt; an unfinished one resumes from its checkpoint to the table an uninterrupted
# run writes. Tables compress well (evaluation journals), checkpoints do not.
set -euo pipefail
cd "$(dirname "$0")/.."
VGS=${VGS:-.venv/bin/vgs}  # the vgs command (tests point it at their own)
usage="usage: scripts/carry.sh pack RUN FILE | scripts/carry.sh unpack FILE RUN"
PART=${CARRY_PART_BYTES:-4500000}

case "${1:-}" in
pack)
    RUN=${2:?$usage}; FILE=${3:?$usage}
    RUN=${RUN%/}
    [ -d "$RUN" ] || { echo "carry: $RUN is not a folder" >&2; exit 1; }
    NAME=$(basename "$RUN")
    TMP=$(mktemp -d)
    trap 'rm -rf "$TMP"' EXIT
    tar -C "$(dirname "$RUN")" --exclude=tensorboard --exclude=.lock --exclude='.*.tmp' \
        --exclude=checkpoint.pt -cf - "$NAME" | tar -C "$TMP" -xf -
    while IFS= read -r ckpt; do
        dir=$(dirname "$ckpt")
        into="$TMP/$NAME${dir#"$RUN"}"
        if [ -f "$dir/convergence.json" ]; then
            $VGS export-policy "$dir" --out "$into" > /dev/null
            echo "carry: $dir finished: kept as its final network (policy.pt)"
        else
            cp "$ckpt" "$into/"
            echo "carry: $dir unfinished: kept with its checkpoint"
        fi
    done < <(find "$RUN" -name checkpoint.pt | sort)
    mkdir -p "$(dirname "$FILE")"
    tar -C "$TMP" -cf - "$NAME" | xz -9e > "$FILE.tmp"  # xz: the tables pack 10 % smaller
    rm -f "$FILE" "$FILE".part[0-9][0-9]  # what an earlier pack left
    if [ "$(stat -c %s "$FILE.tmp")" -le "$PART" ]; then
        mv "$FILE.tmp" "$FILE"
        echo "carry: $FILE ($(du -h "$FILE" | cut -f1)); commit it, and unpack it on the next machine"
    else
        split -b "$PART" -d -a 2 "$FILE.tmp" "$FILE.part"
        rm "$FILE.tmp"
        echo "carry: $FILE in $(ls "$FILE".part[0-9][0-9] | wc -l) pieces, $FILE.part00 ..." \
             "($(cat "$FILE".part[0-9][0-9] | wc -c) bytes); commit them, and unpack $FILE on" \
             "the next machine"
    fi
    ;;
unpack)
    FILE=${2:?$usage}; RUN=${3:?$usage}
    RUN=${RUN%/}
    PARTS=("$FILE".part[0-9][0-9])
    [ -f "$FILE" ] || [ -f "${PARTS[0]}" ] || {
        echo "carry: $FILE is not a file (nor split in $FILE.part00, ...)" >&2; exit 1; }
    if [ -e "$RUN" ]; then
        echo "carry: $RUN exists; move it away or unpack elsewhere" >&2
        exit 1
    fi
    mkdir -p "$(dirname "$RUN")"
    TMP=$(mktemp -d "$(dirname "$RUN")/.carry.XXXXXX")
    if [ -f "$FILE" ]; then
        tar -C "$TMP" -xf "$FILE"  # xz, or the gzip of files packed before
    else
        cat "${PARTS[@]}" | tar -C "$TMP" -xJf -
    fi
    mv "$TMP"/* "$RUN"  # the one folder pack wrote
    rmdir "$TMP"
    echo "carry: $FILE unpacked as $RUN"
    ;;
*)
    echo "$usage" >&2
    exit 2
    ;;
esac

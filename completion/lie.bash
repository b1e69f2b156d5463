# SPDX-License-Identifier: Apache-2.0
# bash completion for the LIE tools (lie-build, lie-render, rst-update, lie-inspect, ...).
# Options are read from the tool's own --help, so completion follows the tool's version.
_lie_tool()
{
    local cur prev words cword
    if declare -F _init_completion >/dev/null 2>&1; then
        _init_completion -s || return
    else
        cur=${COMP_WORDS[COMP_CWORD]}
        prev=${COMP_WORDS[COMP_CWORD-1]}
    fi
    case $prev in
        -o|--output|--scene|--path|--write-scene|--record|--save|--script|--camera-path)
            COMPREPLY=($(compgen -f -- "$cur"))
            return ;;
        --visibility)
            COMPREPLY=($(compgen -W "lie full" -- "$cur")); return ;;
        --light-sampler)
            COMPREPLY=($(compgen -W "tree power uniform per-emitter" -- "$cur")); return ;;
        --blockers)
            COMPREPLY=($(compgen -W "sampled conservative" -- "$cur")); return ;;
        --compression)
            COMPREPLY=($(compgen -W "zip zips piz rle none" -- "$cur")); return ;;
        --format)
            COMPREPLY=($(compgen -W "exr png" -- "$cur")); return ;;
    esac
    if [[ $cur == -* ]]; then
        local opts
        opts=$("${COMP_WORDS[0]}" --help 2>/dev/null | grep -oE -- '--[a-z][a-z0-9-]*=?' | sort -u)
        COMPREPLY=($(compgen -W "$opts" -- "$cur"))
        [[ ${COMPREPLY[0]} == *= ]] && compopt -o nospace 2>/dev/null
        return
    fi
    if [[ ${COMP_WORDS[0]##*/} == lie-inspect && $COMP_CWORD -eq 1 ]]; then
        COMPREPLY=($(compgen -W "summary verify dump patch diff image" -- "$cur"))
        return
    fi
    COMPREPLY=($(compgen -f -- "$cur"))
}
complete -o filenames -F _lie_tool lie-build lie-render rst-update lie-inspect lie-view lie-animate
